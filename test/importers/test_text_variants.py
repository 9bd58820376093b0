"""TRC/MOT/STO as real exporters write them, each variant built here from the real OpenCap files.

The truth of every variant is the import of the original file: a variant only
re-lays the same tokens (line endings, blank lines, padding, separators,
header spelling) or blanks out known cells, so the parsed numbers must be
identical, NaN exactly where a cell was blanked.
"""

from __future__ import annotations

import numpy as np
import pytest

from hop_impedance.importers import import_opensim
from hop_impedance.importers.opensim_import import read_mot, read_trc

from .conftest import OPENCAP

TRC = OPENCAP / "Subject4_DJ1_markers_trc.txt"
MOT = OPENCAP / "Subject4_DJ1_grf_mot.txt"
pytestmark = pytest.mark.skipif(not TRC.exists(), reason="shared data set opencap_dropjump not present")


def _rows(path):
    return path.read_text(encoding="utf-8").split("\n")


def _write(tmp_path, name, lines, eol="\n", bom=False):
    out = tmp_path / name
    out.write_bytes((("\ufeff" if bom else "") + eol.join(lines)).encode("utf-8"))
    return out


def _padded(line, width=16):
    """MATLAB-style fixed-width line: every tab-separated token right-justified after a space, spaces only."""
    return "".join(" " + c.rjust(width) for c in line.split("\t"))


def _mot_parts():
    lines = _rows(MOT)
    end = next(i for i, ln in enumerate(lines) if ln.strip() == "endheader")
    return lines[:end], lines[end], lines[end + 1], [ln for ln in lines[end + 2 :] if ln.strip()]


@pytest.fixture(scope="module")
def mot_truth():
    return read_mot(MOT)


@pytest.fixture(scope="module")
def trc_truth():
    return read_trc(TRC)


def _same_mot(got, truth):
    assert got.columns == truth.columns
    np.testing.assert_array_equal(got.values, truth.values)


class TestMotVariants:
    def test_issue_case_matlab_crlf_blank_line_padded_columns(self, tmp_path, mot_truth):
        # Issue 19: "data row 1 has 10 values for 0 columns" before this reader.
        head, end, cols, data = _mot_parts()
        path = _write(tmp_path, "matlab.mot", head + [end, "", _padded(cols)] + [_padded(r) for r in data], eol="\r\n")
        _same_mot(read_mot(path), mot_truth)

    def test_tabs_with_trailing_tab_cr_only_and_blank_lines_between_rows(self, tmp_path, mot_truth):
        head, end, cols, data = _mot_parts()
        body = [r + "\t" for r in data]
        body.insert(10, "")
        path = _write(tmp_path, "cr.mot", head + [end + "  ", cols + "\t"] + body, eol="\r")
        _same_mot(read_mot(path), mot_truth)

    def test_header_spellings_and_byte_order_mark(self, tmp_path, mot_truth):
        head, _, cols, data = _mot_parts()
        # Version-1 storage: a name line first, spaces around '=', 'EndHeader' capitalised.
        head = ["Subject4_DJ1_grf"] + [ln.replace("=", " = ") for ln in head]
        got = read_mot(_write(tmp_path, "v1.sto", head + ["EndHeader", cols] + data, bom=True))
        _same_mot(got, mot_truth)
        assert got.header["nRows"] == "269"

    @pytest.mark.parametrize("spelling", ["nan", "NaN", "-nan(ind)", "1.#QNAN", "-1.#IND", ""])
    def test_missing_value_spellings(self, tmp_path, mot_truth, spelling):
        head, end, cols, data = _mot_parts()
        k = mot_truth.columns.index("ground_force_3_vy")
        body = []
        for i, r in enumerate(data):
            cells = r.split("\t")
            if i % 7 == 0:
                cells[k] = spelling
            body.append("\t".join(cells))
        got = read_mot(_write(tmp_path, "nan.mot", head + [end, cols] + body))
        expected = mot_truth.values.copy()
        expected[::7, k] = np.nan
        np.testing.assert_array_equal(got.values, expected)

    def test_empty_last_column_is_a_value_not_a_missing_column(self, tmp_path, mot_truth):
        head, end, cols, data = _mot_parts()
        body = ["\t".join(r.split("\t")[:-1] + [""]) for r in data]
        got = read_mot(_write(tmp_path, "lastempty.mot", head + [end, cols] + body))
        assert np.isnan(got.values[:, -1]).all()
        np.testing.assert_array_equal(got.values[:, :-1], mot_truth.values[:, :-1])

    def test_still_refused_with_a_clear_line(self, tmp_path):
        head, end, cols, data = _mot_parts()
        with pytest.raises(ValueError, match="must name the columns"):
            read_mot(_write(tmp_path, "nocols.mot", head + [end] + data))
        with pytest.raises(ValueError, match=r"data row 3 has 27 values for 28 columns"):
            read_mot(_write(tmp_path, "short.mot", head + [end, cols] + data[:2] + [data[2].rsplit("\t", 1)[0]] + data[3:]))
        with pytest.raises(ValueError, match=r"word.mot data row 2: 'x0.01' is not a number"):
            read_mot(_write(tmp_path, "word.mot", head + [end, cols, data[0], "x" + data[1]] + data[2:]))


def _same_trc(got, truth, nan_mask=None):
    assert got.labels == truth.labels and got.rate_hz == truth.rate_hz
    np.testing.assert_array_equal(got.time_s, truth.time_s)
    expected = truth.positions_m.copy()
    if nan_mask is not None:
        expected[nan_mask] = np.nan
    np.testing.assert_array_equal(got.positions_m, expected)


class TestTrcVariants:
    def test_crlf_without_the_blank_line(self, tmp_path, trc_truth):
        lines = [ln for ln in _rows(TRC) if ln.strip()]
        _same_trc(read_trc(_write(tmp_path, "crlf.trc", lines, eol="\r\n")), trc_truth)

    def test_space_padded_columns_and_nan_cells(self, tmp_path, trc_truth):
        lines = [ln for ln in _rows(TRC) if ln.strip()]
        body = []
        for i, r in enumerate(lines[5:]):
            cells = r.split("\t")
            if i % 5 == 0:
                cells[2:5] = ["NaN"] * 3  # first marker (C7) occluded
            body.append(_padded("\t".join(cells), 14))
        # Labels line padded too: the empty cells after each label become spaces.
        head = [lines[0], _padded(lines[1]), _padded(lines[2]), _padded(lines[3]), _padded(lines[4])]
        mask = np.zeros(trc_truth.positions_m.shape, bool)
        mask[::5, 0, :] = True
        _same_trc(read_trc(_write(tmp_path, "padded.trc", head + body)), trc_truth, mask)

    def test_empty_cells_and_rows_cut_short(self, tmp_path, trc_truth):
        # Vicon writes nothing for an occluded marker and stops a row after its last visible one.
        lines = [ln for ln in _rows(TRC) if ln.strip()]
        body = []
        for i, r in enumerate(lines[5:]):
            cells = r.split("\t")
            if i % 4 == 0:
                cells[5:8] = ["", "", ""]  # second marker (L.ASIS)
            if i % 6 == 0:
                cells = cells[: 2 + 3 * 50]  # last marker (r_toe) absent
            body.append("\t".join(cells))
        mask = np.zeros(trc_truth.positions_m.shape, bool)
        mask[::4, 1, :] = True
        mask[::6, 50, :] = True
        _same_trc(read_trc(_write(tmp_path, "vicon.trc", lines[:5] + body)), trc_truth, mask)

    def test_without_the_coordinate_line(self, tmp_path, trc_truth):
        lines = [ln for ln in _rows(TRC) if ln.strip()]
        _same_trc(read_trc(_write(tmp_path, "nocoords.trc", lines[:4] + lines[5:])), trc_truth)


def test_matlab_variants_import_to_the_same_recording(tmp_path):
    """The whole import (mapping, frames, plates) of the CRLF/padded variants equals the original's."""
    head, end, cols, data = _mot_parts()
    mot = _write(tmp_path, "grf.mot", head + [end, "", _padded(cols)] + [_padded(r) for r in data], eol="\r\n")
    trc_lines = [ln for ln in _rows(TRC) if ln.strip()]
    trc = _write(tmp_path, "m.trc", trc_lines[:1] + [_padded(x, 14) for x in trc_lines[1:]], eol="\r\n")
    a = import_opensim(TRC, MOT, "opencap_right", mass_kg=60.0)
    b = import_opensim(trc, mot, "opencap_right", mass_kg=60.0)
    np.testing.assert_array_equal(b.force.force_n, a.force.force_n)
    np.testing.assert_array_equal(b.force.torque_nm, a.force.torque_nm)
    np.testing.assert_array_equal(b.markers.positions_m, a.markers.positions_m)
    assert (b.subject.body_mass_kg, b.subject.body_height_m) == (a.subject.body_mass_kg, a.subject.body_height_m)
