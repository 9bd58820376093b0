"""launch/pipeline.launch.py checked without launch_ros (not on PyPI): parsed with ast and matched
against setup.py's entry points, the parameters each node really declares (built with rclpy) and
the YAML files in config/ that setup.py installs."""

import ast
from pathlib import Path

import yaml

from test.ros.test_colcon_workspace import console_scripts, entry_modules

ROOT = Path(__file__).resolve().parents[2]
LAUNCH = ROOT / "launch" / "pipeline.launch.py"
#: Keyword arguments of the launch file's node() helper that are not node parameters.
HELPER_KWARGS = {"condition", "params_file"}


def _strings(node: ast.AST) -> list[str]:
    return [n.value for n in ast.walk(node) if isinstance(n, ast.Constant) and isinstance(n.value, str)]


def launched_nodes() -> list[dict]:
    """Each ``node("exe", ...)`` call: executable, parameter overrides, params file, launch configurations used."""
    tree = ast.parse(LAUNCH.read_text())
    default_file = next(s for s in _strings(tree) if s.endswith(".yaml"))  # the helper's default: pipeline.yaml
    out = []
    for call in ast.walk(tree):
        if isinstance(call, ast.Call) and isinstance(call.func, ast.Name) and call.func.id == "node":
            files = [s for kw in call.keywords if kw.arg == "params_file" for s in _strings(kw.value)]
            out.append({
                "executable": ast.literal_eval(call.args[0]),
                "overrides": [kw.arg for kw in call.keywords if kw.arg not in HELPER_KWARGS],
                "params_file": next((f for f in files if f.endswith(".yaml")), default_file),
            })
    return out


def declared_parameters(executables: list[str], modules: dict[str, str], tmp: Path) -> dict[str, set[str]]:
    """Parameters each node really declares: the node class of the entry point's module, built with rclpy
    (overrides only where a node needs an input or would open a viewer), then listed."""
    import importlib

    import rclpy
    from rclpy.node import Node
    from rclpy.parameter import Parameter

    needs = {"replay": {"recording": str(ROOT / "recordings" / "sim_2p20hz_hard.mcap"), "wait_for_subscribers_s": 0.0},
             "recorder": {"output": str(tmp / "rec.mcap")}, "rerun_bridge": {"save_path": str(tmp / "x.rrd")}}
    out = {}
    context = rclpy.Context()
    rclpy.init(context=context)
    try:
        for exe in executables:
            module = importlib.import_module(modules[exe])
            cls = next(v for v in vars(module).values()
                       if isinstance(v, type) and issubclass(v, Node) and v is not Node and v.__module__ == module.__name__)
            node = cls(context=context, parameter_overrides=[Parameter(k, value=v) for k, v in needs.get(exe, {}).items()])
            out[exe] = set(node.list_parameters([], 0).names)
            if hasattr(node, "stop"):
                node.stop()
            node.destroy_node()
    finally:
        rclpy.shutdown(context=context)
    return out


def test_every_launched_executable_is_an_entry_point_with_its_parameters(tmp_path):
    nodes = launched_nodes()
    scripts, modules = set(console_scripts()), entry_modules()
    assert {"stance_detector", "inverse_dynamics", "impedance_estimator", "recorder", "replay",
            "plate_combiner", "mocap4r2_adapter"} <= {n["executable"] for n in nodes}
    for n in nodes:
        assert n["executable"] in scripts, f"launch starts {n['executable']}, setup.py has no such console script"
    declared = declared_parameters([n["executable"] for n in nodes], modules, tmp_path)
    installed = _installed_config()
    for_all: dict[str, set[str]] = {}  # params file -> parameters its "/**" section sets
    users: dict[str, set[str]] = {}  # params file -> parameters declared by the nodes that load it
    for n in nodes:
        exe, pfile = n["executable"], n["params_file"]
        unknown = set(n["overrides"]) - declared[exe]
        assert not unknown, f"launch passes {sorted(unknown)} to {exe}, which declares no such parameter"
        assert pfile in installed, f"{pfile} is not installed by setup.py from config/"
        doc = yaml.safe_load((ROOT / "config" / pfile).read_text())
        params = set((doc.get(exe) or {}).get("ros__parameters", {}))
        assert params - declared[exe] == set(), (
            f"config/{pfile} [{exe}] sets {sorted(params - declared[exe])}, not declared by {exe}")
        if pfile != "pipeline.yaml":
            assert params, f"config/{pfile} has no parameters for {exe}"
        for_all[pfile] = set((doc.get("/**") or {}).get("ros__parameters", {}))
        users.setdefault(pfile, set()).update(declared[exe])
    for pfile, params in for_all.items():
        assert params <= users[pfile], f"config/{pfile} [/**] sets {sorted(params - users[pfile])}, declared by no node using it"


def test_every_launch_configuration_is_declared():
    tree = ast.parse(LAUNCH.read_text())
    declared, used = set(), set()
    for call in ast.walk(tree):
        if isinstance(call, ast.Call) and isinstance(call.func, ast.Name) and call.args:
            if call.func.id == "DeclareLaunchArgument":
                declared.add(ast.literal_eval(call.args[0]))
            elif call.func.id == "LaunchConfiguration":
                used.add(ast.literal_eval(call.args[0]))
    assert used <= declared, f"undeclared launch arguments {sorted(used - declared)}"


def _installed_config() -> set[str]:
    """config/ files setup.py's data_files install (its glob, evaluated here), as file names."""
    text = (ROOT / "setup.py").read_text()
    assert 'glob("config/*.yaml")' in text and 'glob("launch/*.py")' in text
    return {p.name for p in (ROOT / "config").glob("*.yaml")}
