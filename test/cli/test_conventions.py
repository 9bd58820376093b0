"""The CLI's one set of conventions (issue 20), checked on the real argparse parser.

- every flag a message, help text or docstring in hop_impedance/ names exists on the sub-command it is about;
- renamed flags still work, store what the new flag stores, and warn on stderr;
- defaults come from the core's option dataclasses, and building the parser imports none of the heavy modules;
- ``demo`` runs from any directory; the version is written once (package.xml).
"""

from __future__ import annotations

import argparse
import ast
import dataclasses
import importlib.metadata
import os
import re
import subprocess
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

import pytest

from hop_impedance.cli.conventions import DeprecatedAlias
from hop_impedance.cli.main import COMMAND_MODULES, build_parser, main

ROOT = Path(__file__).resolve().parents[2]
PACKAGE = ROOT / "hop_impedance"
COMMANDS = set(COMMAND_MODULES)

#: A flag: two dashes, a lower-case name (not part of a longer word or of "---").
FLAG = re.compile(r"(?<![\w-])--([a-z][a-z0-9-]*)")
#: A sub-command named in a text ("hop-impedance CMD", a ``CMD --flag`` literal), or a script ("bench/x.py"),
#: whose flags are not ours. Either holds until the phrase ends (END), across wrapped lines.
NAMED = re.compile(r"(?:hop-impedance\s+|``)(" + "|".join(sorted(COMMANDS)) + r")\s|([\w/.-]+\.py)\b")
END = re.compile(r"``|\)|;|\.\s|\n\s*\n|\n\s*- ")
ANY = "*"  # a hint that names no sub-command, in a module not tied to one: the flag must exist on some sub-command

#: The sub-command a module's hints are about, when the text does not name one.
MODULE_COMMAND = {
    "hop_impedance/importers/": "import",
    "hop_impedance/io/recording_io.py": "analyze",  # a missing /subject: analyze's --mass-kg/--height-m
    "hop_impedance/input_checks.py": "analyze",  # the cut-off rule names analyze's --cutoff-hz
    "hop_impedance/batch/": "batch",
}
#: Modules whose dashes are not hop-impedance flags (a text naming "hop-impedance CMD" there is still checked).
NOT_OURS = {
    "hop_impedance/nodes/": "ROS 2 command lines (--ros-args, --params-file of ros2 run) and rclpy's own --help",
    "hop_impedance/viz/screenshot.py": "its own small argparse entry point (IN.rrd OUT.png [--time-s T])",
}


def _subcommands() -> dict[str, argparse.ArgumentParser]:
    (sub,) = [a for a in build_parser()._actions if isinstance(a, argparse._SubParsersAction)]
    return dict(sub.choices)


def _flags(parser: argparse.ArgumentParser) -> set[str]:
    """The flags a hint may name: every option but the deprecated aliases."""
    return {s for a in parser._actions if not isinstance(a, DeprecatedAlias) for s in a.option_strings}


def _texts(tree: ast.AST):
    """(line, text) of every string in a module: constants and f-strings (with {} for the values), docstrings
    included; the option strings an ``add_argument`` call defines are left out (they exist by definition)."""
    defined = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute) and node.func.attr == "add_argument":
            defined.update(id(a) for a in node.args)
    inner = {id(v) for node in ast.walk(tree) if isinstance(node, ast.JoinedStr) for v in node.values}
    for node in ast.walk(tree):
        if id(node) in defined or id(node) in inner:
            continue
        if isinstance(node, ast.Constant) and isinstance(node.value, str):
            yield node.lineno, node.value
        elif isinstance(node, ast.JoinedStr):
            yield node.lineno, "".join(v.value if isinstance(v, ast.Constant) else "{}" for v in node.values)


def _default_command(rel: str) -> str | None:
    """The sub-command of a module's unnamed hints; None where its dashes are not ours."""
    if any(rel.startswith(prefix) for prefix in NOT_OURS):
        return None
    match = re.fullmatch(r"hop_impedance/cli/(\w+)_cmd\.py", rel)
    if match:
        return match.group(1)
    return next((cmd for prefix, cmd in MODULE_COMMAND.items() if rel.startswith(prefix)), ANY)


def flags_named(text: str, default: str | None) -> list[tuple[str, str]]:
    """(sub-command, flag) of each flag in ``text``; a named sub-command or script holds until its phrase ends."""
    found = []
    command = default
    for m in re.finditer(f"{NAMED.pattern}|{FLAG.pattern}|(?P<end>{END.pattern})", text):
        if m.group(1) or m.group(2):
            command = m.group(1)  # a script's flags (group 2) are not checked
        elif m.group("end"):
            command = default
        elif command is not None:
            found.append((command, "--" + m.group(3)))
    return found


def hint_flags():
    """(file:line, sub-command or ANY, flag, old names allowed) of every flag named in hop_impedance/'s strings.

    A deprecated alias may be named only where the text says it is deprecated, or by a string that is the flag
    alone (the code defining or merging the alias); a hint for users names the current flag.
    """
    found = []
    for path in sorted(PACKAGE.rglob("*.py")):
        rel = path.relative_to(ROOT).as_posix()
        for line, text in _texts(ast.parse(path.read_text(encoding="utf-8"))):
            old_ok = "deprecated" in text.lower() or FLAG.fullmatch(text) is not None
            found += [(f"{rel}:{line}", command, flag, old_ok)
                      for command, flag in flags_named(text, _default_command(rel))]
    return found


def test_every_flag_a_hint_names_exists_on_its_sub_command():
    parsers = _subcommands()
    flags = {name: _flags(p) | {"--help"} for name, p in parsers.items()}
    flags[ANY] = set().union(*flags.values())
    with_old = {name: {s for a in p._actions for s in a.option_strings} | {"--help"} for name, p in parsers.items()}
    with_old[ANY] = set().union(*with_old.values())
    hints = hint_flags()
    assert len(hints) > 100  # the walk sees the package's messages (not an empty glob)
    assert {h[1] for h in hints} >= {"analyze", "import", "pipeline", "simulate", "view", "batch", "discover"}
    wrong = [f"{where}: {cmd} has no {flag}" for where, cmd, flag, old_ok in hints
             if flag not in (with_old if old_ok else flags)[cmd]]
    assert not wrong


def test_the_walk_catches_a_flag_that_does_not_exist():
    """The checker itself: the issue's stale hints (--marker-map, simulate's --mass) are caught on the real parser."""
    text = ('raise ValueError(f"{p}: names differ; give a mapping, --marker-map, or run hop-impedance simulate '
            '--mass 60 (bench/x.py --slowest); then --out")\n')
    ((_, found),) = list(_texts(ast.parse(text)))
    assert flags_named(found, "import") == [("import", "--marker-map"), ("simulate", "--mass"), ("import", "--out")]
    wrapped = "Not the default (bench/simulator_realism.py\n    --seed-like measures it). Use ``hop-impedance\n    view --rrd``."
    assert flags_named(wrapped, "*") == [("view", "--rrd")]
    flags = {name: _flags(p) for name, p in _subcommands().items()}
    assert "--marker-map" not in flags["import"] and "--markers" in flags["import"]
    assert "--mass" not in flags["simulate"] and "--mass-kg" in flags["simulate"]  # --mass is a deprecated alias


@pytest.mark.parametrize("old, new, value", [
    (["pipeline", "--recording", "r.mcap"], ["pipeline", "r.mcap"], ("recording_flag", "r.mcap")),
    (["demo", "--recording", "r.mcap"], ["demo", "r.mcap"], ("recording_flag", "r.mcap")),
    (["simulate", "--out", "o.mcap", "--mass", "61.5"], ["simulate", "--out", "o.mcap", "--mass-kg", "61.5"],
     ("mass_kg", 61.5)),
    (["simulate", "--out", "o.mcap", "--height", "1.7"], ["simulate", "--out", "o.mcap", "--height-m", "1.7"],
     ("height_m", 1.7)),
    (["view", "r.mcap", "--save", "o.rrd"], ["view", "r.mcap", "--rrd", "o.rrd"], ("rrd", "o.rrd")),
    (["discover", "r.mcap", "--json", "-", "--rerun", "o.rrd"], ["discover", "r.mcap", "--json", "-", "--rrd", "o.rrd"],
     ("rrd", "o.rrd")),
    (["pipeline", "r.mcap", "--rerun-save", "o.rrd"], ["pipeline", "r.mcap", "--rrd", "o.rrd"], ("rrd", "o.rrd")),
    (["pipeline", "r.mcap", "--rerun-url", "rerun+http://127.0.0.1:9876/proxy"],
     ["pipeline", "r.mcap", "--connect", "rerun+http://127.0.0.1:9876/proxy"], ("connect", "rerun+http://127.0.0.1:9876/proxy")),
])
def test_renamed_flags_still_work_and_warn(old, new, value, capsys):
    parser = build_parser()
    got_new = parser.parse_args(new)
    assert capsys.readouterr().err == ""
    got_old = parser.parse_args(old)
    err = capsys.readouterr().err
    flag = next(a for a in old if a.startswith("--") and a not in new)
    assert err.count("\n") == 1 and f"warning: {flag} is deprecated; use " in err
    name, expected = value
    assert getattr(got_old, name) == expected
    if name != "recording_flag":  # the positional and its old flag are merged when the command runs
        assert vars(got_old) == vars(got_new)


def test_old_and_new_recording_together_is_a_one_line_error(capsys):
    assert main(["pipeline", "a.mcap", "--recording", "b.mcap"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err[-1] == ("hop-impedance pipeline: error: give the recording once: positionally (a.mcap) or with the "
                       "deprecated --recording (b.mcap)")
    assert main(["pipeline"]) == 2
    assert capsys.readouterr().err.strip() == "hop-impedance pipeline: error: no recording given: hop-impedance pipeline REC.mcap"


def test_deprecated_aliases_are_hidden_from_help():
    parsers = _subcommands()
    for name, old in (("pipeline", "--recording"), ("pipeline", "--rerun-save"), ("pipeline", "--rerun-url"),
                      ("simulate", "--mass"), ("simulate", "--height"), ("view", "--save"), ("discover", "--rerun")):
        text = parsers[name].format_help()
        assert not re.search(re.escape(old) + r"(?![\w-])", text), (name, old)
    assert "--rrd" in parsers["view"].format_help() and "--mass-kg" in parsers["simulate"].format_help()


def test_defaults_are_the_core_defaults():
    """Parsed with no options, each command's settings equal the core's own defaults (one place for each)."""
    from hop_impedance.batch.task import BatchOptions
    from hop_impedance.biomech.analysis import AnalysisOptions
    from hop_impedance.discovery.workflow import MAX_STEPS
    from hop_impedance.nodes.runner import PipelineConfig
    from hop_impedance.simulation.scenarios import SEED_SUBJECT, Effects
    from hop_impedance.simulation.sensors import SensorConfig

    p = build_parser()
    a = p.parse_args(["analyze", "r.mcap", "--json", "-"])
    assert (a.cutoff_hz, a.max_gap_s) == (AnalysisOptions().marker_cutoff_hz, AnalysisOptions().max_gap_s) == (12.0, 0.05)
    b = p.parse_args(["batch", "d", "--out", "o"])
    assert (b.cutoff_hz, b.max_gap_s) == (BatchOptions().cutoff_hz, BatchOptions().max_gap_s) == (a.cutoff_hz, a.max_gap_s)
    c = p.parse_args(["pipeline", "r.mcap"])
    config = PipelineConfig("r.mcap")
    assert (c.out, c.rate, c.timeout) == (config.out_dir, config.rate, config.timeout_s)
    d = p.parse_args(["discover", "r.mcap", "--json", "-"])
    assert d.max_steps == MAX_STEPS
    s = p.parse_args(["simulate", "--out", "o.mcap"])
    assert (s.mass_kg, s.height_m) == (SEED_SUBJECT.body_mass_kg, SEED_SUBJECT.body_height_m) == (54.8, 1.63)
    effects = Effects()
    for f in dataclasses.fields(Effects):
        if f.name != "angle_dependent_stiffness":  # --law seed|constant
            assert getattr(s, f.name) == getattr(effects, f.name), f.name
    sensors = SensorConfig()
    assert (s.force_rate, s.marker_rate, s.force_offset, s.marker_delay, s.occlusions) == (
        sensors.force_rate_hz, sensors.marker_rate_hz, sensors.force_offset_n, sensors.marker_time_offset_s,
        sensors.occlusions_per_s)
    # the help shows the value it read
    assert "(Hz, default 12.0)" in " ".join(_subcommands()["analyze"].format_help().split())


def test_building_the_parser_imports_nothing_heavy():
    code = ("import sys; from hop_impedance.cli.main import build_parser; p = build_parser(); p.format_help(); "
            "print(sorted({m.split('.')[0] for m in sys.modules} & {'numpy', 'scipy', 'rclpy', 'rerun', 'dask'}))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60, cwd=ROOT)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == "[]"


def test_demo_runs_from_another_directory(tmp_path):
    """The bundled recording is found next to the package, not in the current directory."""
    env = {**os.environ, "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST", "HOME": str(tmp_path)}
    run = subprocess.run([sys.executable, "-m", "hop_impedance.cli", "demo", "--rrd", "", "--out", "out"],
                         cwd=tmp_path, env=env, capture_output=True, text=True, timeout=120)
    assert run.returncode == 0, run.stdout + run.stderr
    assert f"replaying {ROOT / 'recordings' / 'sim_2p20hz_hard.mcap'}" in run.stdout
    assert sum(line.rstrip().endswith("| accepted") for line in run.stdout.splitlines()) == 10
    assert (tmp_path / "out" / "pipeline.mcap").stat().st_size > 0


def test_version_is_written_once_in_package_xml():
    import hop_impedance

    written = ET.parse(ROOT / "package.xml").findtext("version")
    assert hop_impedance.__version__ == written == importlib.metadata.version("hop_impedance")
    out = subprocess.run([sys.executable, "-m", "hop_impedance.cli", "--version"], capture_output=True, text=True,
                         timeout=60)
    assert out.stdout.strip() == f"hop-impedance {written}"
    literal = re.compile(r"""['"]""" + re.escape(written) + r"""['"]""")
    assert [p for p in [ROOT / "setup.py", *PACKAGE.rglob("*.py")] if literal.search(p.read_text(encoding="utf-8"))] == []


def test_package_xml_lists_the_runtime_packages():
    deps = {e.text for e in ET.parse(ROOT / "package.xml").getroot() if e.tag in ("depend", "exec_depend")}
    for name in ("osqp", "mcap", "ezc3d", "numpy", "scipy", "yaml", "matplotlib"):
        assert any(re.fullmatch(rf"python3-{name}(-pip)?", d) for d in deps), name
    assert "mcap-ros2-support" in deps
