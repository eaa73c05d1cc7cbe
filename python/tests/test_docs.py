"""docs/python.md documents every parameter of every public function, method and class: its API
table has a row naming each callable, and that row names each of its parameters."""
import inspect
import pathlib
import re

import foveal

DOCS = pathlib.Path(__file__).resolve().parents[2] / "docs" / "python.md"


def _parameters(function):
    """Parameter names of a Python function, or of a nanobind function (from its signature line)."""
    try:
        signature = inspect.signature(function)
        return [p.name for p in signature.parameters.values() if p.name != "self"]
    except (TypeError, ValueError):
        pass
    text = getattr(function, "__nb_signature__", None)
    assert text, f"{function!r}: no signature"
    names = []
    for line in text:
        head = line[0]
        inside = head[head.index("(") + 1: head.rindex(")")]
        for part in re.split(r",\s*(?![^\[]*\])", inside):
            name = part.split(":")[0].split("=")[0].strip().lstrip("*")
            if name and name not in ("self", "/", "*"):
                names.append(name)
    return names


# Results the package makes (their fields are documented with them); no one constructs them
RESULTS = {"Frame", "LoopFrame", "VisionStep", "Recording", "Events", "MachineSnapshot"}


def _public():
    """(documented name, callable) for every public function, class constructor and method."""
    out = []
    modules = [(foveal, "foveal."), (foveal.gaze, "foveal.gaze.")]
    for module, prefix in modules:
        for name in module.__all__:
            item = getattr(module, name)
            if inspect.isclass(item):
                if name not in RESULTS:
                    out.append((prefix + name, item.__init__))
                for attribute, member in vars(item).items():
                    if attribute.startswith("_") or isinstance(member, (property, staticmethod)):
                        continue
                    if callable(member) and not inspect.isclass(member):
                        out.append((f"{name}.{attribute}", member))
            elif callable(item) and not isinstance(item, type):
                out.append((prefix + name, item))
    return out


def test_every_public_parameter_is_documented():
    rows = [line for line in DOCS.read_text(encoding="utf-8").splitlines() if line.startswith("| `")]
    missing = []
    for name, function in _public():
        row = next((r for r in rows if f"`{name}(" in r or f"`{name}`" in r), None)
        if row is None and "." in name and not name.startswith("foveal"):  # a method, in its class's row
            owner, method = name.split(".", 1)
            row = next((r for r in rows if re.search(rf"`(foveal\.(gaze\.)?)?{owner}[`(]", r) and f".{method}(" in r), None)
        if row is None:
            missing.append(f"{name}: no row in the API table")
            continue
        for parameter in _parameters(function):
            if not re.search(rf"\b{re.escape(parameter)}\b", row):
                missing.append(f"{name}: parameter '{parameter}' not documented")
    assert not missing, "\n".join(missing)


def test_the_check_sees_parameters_of_both_kinds():
    assert "max_rays" in _parameters(foveal.Renderer.render)  # nanobind
    assert "encoding" in _parameters(foveal.perceive)          # Python
