"""Marker mapping: from a lab's marker labels to the contract's six markers.

A mapping is a small YAML file (ready ones ship in
``hop_impedance/data/marker_maps/``; see ``docs/importing.md``)::

    name: opencap_right
    markers:            # contract name -> lab labels, first one present wins
      toe: [r_5meta]
      heel: [r_calc]
      ...
    forward_pairs:      # rear -> front label pairs to detect the heading
      - [r_calc, r_toe]
    virtual_markers:    # optional: points built by published rules, usable as labels above
      R_HJC_reg: {method: harrington2007, side: right, inputs: {rasi: [r.ASIS], ...}}
    lower_to_sole: [toe]  # optional: markers moved down to the sole (see session.py)

Labels match exactly first, then ignoring case and a ``Subject:`` prefix (as
Vicon Nexus writes ``Anna:RTOE``). Virtual markers are described in
:mod:`hop_impedance.importers.virtual_markers`.
"""

from __future__ import annotations

import difflib
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import yaml

from hop_impedance.importers.virtual_markers import (
    VirtualMarker,
    compute,
    missing_inputs,
    resolve_inputs,
    virtual_from_dict,
)
from hop_impedance.recording import MARKER_NAMES

#: Folder holding the ready mappings shipped with the package.
MAPPINGS_DIR = Path(__file__).resolve().parent.parent / "data" / "marker_maps"


class MissingMarkersError(ValueError):
    """The session lacks labels that the marker mapping needs; the message names them."""


@dataclass(frozen=True)
class MarkerMapping:
    """Lab labels for each contract marker.

    Attributes
    ----------
    name : str
    candidates : dict of str -> tuple of str
        For each of :data:`MARKER_NAMES`, the lab labels to try, in order.
    forward_pairs : tuple of (str, str)
        Rear -> front label pairs whose horizontal direction is the heading.
    virtual : tuple of VirtualMarker
        Points built from other markers, in declaration order (a later one may use an earlier one).
    lower_to_sole : tuple of str
        Contract markers to move down to the sole after the import
        (:func:`~hop_impedance.importers.session.lower_to_sole`).
    """

    name: str
    candidates: dict[str, tuple[str, ...]]
    forward_pairs: tuple[tuple[str, str], ...] = ()
    virtual: tuple[VirtualMarker, ...] = ()
    lower_to_sole: tuple[str, ...] = ()


def available_mappings() -> list[str]:
    """Names of the ready mappings shipped with the package (sorted)."""
    return sorted(p.stem for p in MAPPINGS_DIR.glob("*.yaml"))


def load_marker_mapping(name_or_path: str | Path) -> MarkerMapping:
    """Load a mapping by shipped name (``"opencap_right"``) or YAML path.

    Raises
    ------
    ValueError
        If the name is unknown, or the file lacks a contract marker or is malformed.
    """
    path = Path(name_or_path)
    if not path.suffix and not path.exists():
        path = MAPPINGS_DIR / f"{name_or_path}.yaml"
        if not path.exists():
            raise ValueError(
                f"unknown marker mapping {str(name_or_path)!r}; shipped ones: {', '.join(available_mappings())}, "
                "or give a YAML file"
            )
    with open(path, encoding="utf-8") as fh:
        doc = yaml.safe_load(fh) or {}
    return mapping_from_dict(doc, default_name=path.stem, where=str(path))


def mapping_from_dict(doc: dict, default_name: str = "custom", where: str = "mapping") -> MarkerMapping:
    """Build a :class:`MarkerMapping` from a parsed YAML document (see module docstring)."""
    markers = doc.get("markers")
    if not isinstance(markers, dict):
        raise ValueError(f"{where}: needs a 'markers' table from contract names to lab labels")
    missing = [m for m in MARKER_NAMES if m not in markers]
    unknown = [m for m in markers if m not in MARKER_NAMES]
    if missing or unknown:
        raise ValueError(
            f"{where}: 'markers' must map exactly the contract markers {', '.join(MARKER_NAMES)}"
            + (f"; missing {', '.join(missing)}" if missing else "")
            + (f"; unknown {', '.join(map(str, unknown))}" if unknown else "")
        )
    candidates = {
        m: tuple(str(v) for v in (markers[m] if isinstance(markers[m], list) else [markers[m]])) for m in MARKER_NAMES
    }
    pairs = tuple((str(a), str(b)) for a, b in doc.get("forward_pairs", []) or [])
    virtual_doc = doc.get("virtual_markers") or {}
    if not isinstance(virtual_doc, dict):
        raise ValueError(f"{where}: 'virtual_markers' must be a table from names to definitions")
    virtual = tuple(virtual_from_dict(n, d, where) for n, d in virtual_doc.items())
    sole = tuple(str(m) for m in doc.get("lower_to_sole", []) or [])
    if bad := [m for m in sole if m not in MARKER_NAMES]:
        raise ValueError(f"{where}: 'lower_to_sole' names unknown contract markers: {', '.join(bad)}")
    return MarkerMapping(str(doc.get("name", default_name)), candidates, pairs, virtual, sole)


def _normalise(label: str) -> str:
    return label.split(":")[-1].strip().lower()


def find_label(labels: list[str] | tuple[str, ...], wanted: str) -> int | None:
    """Index of ``wanted`` among ``labels``: exact, else case- and prefix-insensitive; None if absent."""
    if wanted in labels:
        return list(labels).index(wanted)
    norm = [_normalise(x) for x in labels]
    w = _normalise(wanted)
    return norm.index(w) if w in norm else None


def available_labels(labels: list[str] | tuple[str, ...], mapping: MarkerMapping) -> list[str]:
    """The file's labels followed by the names of the mapping's virtual markers that its labels can build."""
    out = list(labels)
    for vm in mapping.virtual:
        if resolve_inputs(vm, out, find_label) is not None:
            out.append(vm.name)
    return out


def with_virtual_markers(
    labels: list[str] | tuple[str, ...],
    positions: np.ndarray,
    mapping: MarkerMapping,
    parameters: dict[str, float] | None = None,
    sex: str = "female",
    only_needed: bool = True,
) -> tuple[list[str], np.ndarray, dict[str, str]]:
    """Append the mapping's virtual markers to a session's markers.

    With ``only_needed`` (default) only those that feed a contract marker
    (directly or as an input of one that does) are built, so a rule the
    import does not use cannot stop it (e.g. a Davis hip joint centre without
    a leg length in a file that exports its own); otherwise every buildable one.

    Raises
    ------
    MissingMarkersError
        If a contract marker has none of its labels (named, as :func:`resolve_labels`).
    ValueError
        If a needed virtual marker cannot be built (e.g. no leg length).

    Returns
    -------
    labels : list of str, length L + V
    positions : ndarray, shape (M, L + V, 3)
    notes : dict of str -> str
        Virtual marker name -> how it was built (method, citation, inputs).
    """
    out_labels, out_pos, notes = list(labels), positions, {}
    needed = _needed_virtual(labels, mapping) if only_needed else {vm.name for vm in mapping.virtual}
    for vm in mapping.virtual:
        picked = resolve_inputs(vm, out_labels, find_label)
        if picked is None or vm.name not in needed:
            continue
        pos, note = compute(vm, out_labels, out_pos, picked, parameters, sex)
        out_labels.append(vm.name)
        out_pos = np.concatenate([out_pos, pos[:, None, :]], axis=1)
        notes[vm.name] = note
    return out_labels, out_pos, notes


def _needed_virtual(labels: list[str] | tuple[str, ...], mapping: MarkerMapping) -> set[str]:
    """Names of the virtual markers that feed the contract markers, inputs of inputs included."""
    avail = available_labels(labels, mapping)
    virtual = {vm.name: vm for vm in mapping.virtual}
    stack = [avail[i] for i in resolve_labels(labels, mapping).values() if avail[i] in virtual]
    need: set[str] = set()
    while stack:
        name = stack.pop()
        if name in need:
            continue
        need.add(name)
        for idx in (resolve_inputs(virtual[name], avail, find_label) or {}).values():
            stack += [avail[i] for i in idx if avail[i] in virtual]
    return need


def source_notes(labels: list[str], mapping: MarkerMapping, virtual_notes: dict[str, str]) -> list[str]:
    """One line per contract marker: which label or virtual marker fed it (``labels`` include virtual ones)."""
    idx = resolve_labels(labels, mapping)
    lines = []
    for name in MARKER_NAMES:
        label = labels[idx[name]]
        how = f" = {virtual_notes[label]}" if label in virtual_notes else ""
        lines.append(f"{name} <- {label}{how}")
    return lines


def resolve_labels(labels: list[str] | tuple[str, ...], mapping: MarkerMapping) -> dict[str, int]:
    """Column index of each contract marker among the file's labels.

    Returns
    -------
    dict of str -> int
        One entry per contract marker.

    Raises
    ------
    MissingMarkersError
        Naming every contract marker that has none of its labels in the file,
        the labels tried and the closest labels present.
    """
    labels = available_labels(labels, mapping)
    found: dict[str, int] = {}
    problems = []
    for name in MARKER_NAMES:
        hits = [h for h in (find_label(labels, c) for c in mapping.candidates[name]) if h is not None]
        if hits:
            found[name] = hits[0]
            continue
        near = sorted(
            {x for c in mapping.candidates[name] for x in difflib.get_close_matches(c, list(labels), n=2, cutoff=0.6)}
        )
        virtual = {vm.name: vm for vm in mapping.virtual}
        lacks = [
            f"{c} needs {missing_inputs(virtual[c], labels, find_label)}" for c in mapping.candidates[name] if c in virtual
        ]
        problems.append(
            f"{name} (tried {', '.join(mapping.candidates[name])}"
            + (f"; {'; '.join(lacks)}" if lacks else "")
            + (f"; closest in file: {', '.join(near)}" if near else "")
            + ")"
        )
    if problems:
        raise MissingMarkersError(
            f"marker mapping {mapping.name!r}: missing markers: {'; '.join(problems)}. "
            "Give another mapping (--markers NAME or YAML)"
        )
    return found


def contract_markers(labels: list[str] | tuple[str, ...], positions: np.ndarray, mapping: MarkerMapping) -> np.ndarray:
    """The six contract markers picked out of a lab session.

    Parameters
    ----------
    labels : sequence of str, length L
        The file's marker labels.
    positions : ndarray, shape (M, L, 3)
        All markers' positions (any unit, lab frame; NaN for occluded).
    mapping : MarkerMapping

    Returns
    -------
    ndarray, shape (M, 6, 3)
        Positions in :data:`MARKER_NAMES` order.
    """
    idx = resolve_labels(labels, mapping)
    return positions[:, [idx[m] for m in MARKER_NAMES], :]


def forward_pair_positions(
    labels: list[str] | tuple[str, ...], positions: np.ndarray, mapping: MarkerMapping
) -> tuple[list[np.ndarray], list[np.ndarray]]:
    """Rear and front positions, shape (M, 3) each, of the mapping's forward pairs present in the file.

    Falls back to the mapped heel -> toe when none of the pairs is present.
    """
    rear, front = [], []
    for a, b in mapping.forward_pairs:
        ia, ib = find_label(labels, a), find_label(labels, b)
        if ia is not None and ib is not None:
            rear.append(positions[:, ia, :])
            front.append(positions[:, ib, :])
    if not rear:
        idx = resolve_labels(labels, mapping)
        rear.append(positions[:, idx["heel"], :])
        front.append(positions[:, idx["toe"], :])
    return rear, front


def choose_mapping(labels: list[str] | tuple[str, ...], spec: str | Path | MarkerMapping | None = None) -> MarkerMapping:
    """The mapping to use for a file's labels.

    Parameters
    ----------
    labels : sequence of str
        The file's marker labels.
    spec : str, Path, MarkerMapping or None
        A mapping, a shipped name or a YAML path. None tries the shipped
        mappings in :func:`available_mappings` order and takes the first whose
        six markers are all present (``*_right`` before ``*_left``).

    Raises
    ------
    MissingMarkersError
        If ``spec`` is given and lacks markers, or no shipped mapping fits
        (the message lists what each one misses).
    """
    if isinstance(spec, MarkerMapping):
        resolve_labels(labels, spec)
        return spec
    if spec is not None:
        mapping = load_marker_mapping(spec)
        resolve_labels(labels, mapping)
        return mapping
    names = sorted(available_mappings(), key=lambda n: (n.endswith("_left"), n))
    reasons = []
    for name in names:
        mapping = load_marker_mapping(name)
        try:
            resolve_labels(labels, mapping)
        except MissingMarkersError as exc:
            reasons.append(str(exc))
            continue
        return mapping
    raise MissingMarkersError(
        "no shipped marker mapping fits this file's labels; write a YAML mapping (see docs/importing.md). "
        + " | ".join(reasons)
    )
