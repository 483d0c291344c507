"""The package's layers (docs/architecture.md, "Package map"), checked on every import
statement of the source: the top-level shared modules, the inputs (scene, daylight), the
engine, then io, workplane, viz and the command line."""

import ast
from pathlib import Path

import lbl_illum

PACKAGE = Path(lbl_illum.__file__).resolve().parent
SHARED = {"errors", "photometry", "options", "optional", "_version", "_public"}
#: What each layer may import of the package besides the shared modules and itself.
ALLOWED = {
    "shared": set(),
    "scene": {"daylight", "io.files"},
    "daylight": {"scene.geometry"},
    "engine": {"scene", "daylight"},
    "glare": {"scene.views", "io.images", "daylight.skymatrix", "daylight.sun"},
    # runs on a cluster: the engine's integrator and records, a worker's scene read from its
    # file, and the cache files' contents as the record sets that travel
    "distributed": {"engine", "scene.scenefile", "io.cachefile"},
}
#: Single modules allowed more: the record store's save/load conveniences, which import the
#: file format when called (the engine itself never reads or writes a cache file).
EXCEPTIONS = {("engine", "cache"): {"io.cachefile"},
              # a Radiance file's ! commands other than xform run with Radiance's programs,
              # found where the export's checks find them
              ("scene", "radfile"): {"io.radiance"}}


def _imports(path: Path):
    """(line, dotted target inside lbl_illum) of every relative import of a module."""
    parts = path.relative_to(PACKAGE).with_suffix("").parts
    here = list(parts[:-1])
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.ImportFrom) and node.level:
            base = here[:len(here) - (node.level - 1)] if node.level > 1 else here
            target = base + (node.module.split(".") if node.module else [])
            if node.module is None:
                for alias in node.names:
                    yield node.lineno, ".".join(target + [alias.name])
            else:
                yield node.lineno, ".".join(target)


def _layer(dotted: str) -> str:
    top = dotted.split(".")[0]
    return "shared" if top in SHARED else top


def test_layers_import_only_what_they_may():
    wrong = []
    for path in sorted(PACKAGE.rglob("*.py")):
        rel = path.relative_to(PACKAGE).with_suffix("").parts
        layer = "shared" if len(rel) == 1 else rel[0]
        if layer not in ALLOWED or rel[-1] in ("__init__", "__main__") and len(rel) == 1:
            continue
        for line, target in _imports(path):
            other = _layer(target)
            extra = EXCEPTIONS.get(rel, set())
            if other in (layer, "shared") or target in ALLOWED[layer] | extra or other in ALLOWED[layer]:
                continue
            wrong.append(f"{'/'.join(rel)}.py:{line} imports {target}")
    assert not wrong, "\n".join(wrong)


def test_every_module_is_in_a_layer_folder_or_shared():
    loose = [p.name for p in PACKAGE.glob("*.py") if p.stem not in SHARED | {"__init__", "__main__"}]
    assert loose == []
