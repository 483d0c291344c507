"""The public surface: what each layer package exports, that the validation studies and
benchmarks use nothing else, and that the studies run from an installed copy (the
packages pyproject.toml installs, laid out as a wheel installs them, outside the checkout)."""

import ast
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

try:
    import tomllib
except ModuleNotFoundError:          # Python 3.10
    import tomli as tomllib

import lbl_illum

ROOT = Path(__file__).resolve().parents[1]
LAYERS = ("scene", "daylight", "engine", "io", "workplane", "viz", "glare", "distributed")
#: Shared top-level modules whose ``__all__`` is public.
SHARED_PUBLIC = ("options", "photometry", "errors", "optional")


def _public_names(module: str) -> set[str]:
    import importlib

    return set(importlib.import_module(module).__all__)


@pytest.mark.parametrize("layer", LAYERS)
def test_every_public_name_of_a_layer_resolves_and_is_listed(layer):
    import importlib

    package = importlib.import_module(f"lbl_illum.{layer}")
    assert package.__all__ == sorted(set(package.__all__)) and package.__all__
    for name in package.__all__:
        value = getattr(package, name)
        assert value is not None, name
        assert name in dir(package)
    with pytest.raises(AttributeError, match="has no attribute 'no_such_name'"):
        getattr(package, "no_such_name")


def test_a_public_name_is_the_object_its_module_defines():
    from lbl_illum.engine import Integrator, render_image
    from lbl_illum.engine.integrator import Integrator as direct
    from lbl_illum.engine.render import render_image as render_direct

    assert Integrator is direct and render_image is render_direct


def _lbl_imports(path: Path):
    """(line, module, names) of every import of lbl_illum in a file (names None: ``import``)."""
    for node in ast.walk(ast.parse(path.read_text(encoding="utf-8"))):
        if isinstance(node, ast.ImportFrom) and node.level == 0 and node.module \
                and (node.module == "lbl_illum" or node.module.startswith("lbl_illum.")):
            yield node.lineno, node.module, [a.name for a in node.names]
        elif isinstance(node, ast.Import):
            for alias in node.names:
                if alias.name.startswith("lbl_illum."):
                    yield node.lineno, alias.name, None


def test_validation_uses_only_the_public_api():
    public = {"lbl_illum": set(lbl_illum.__all__)}
    public.update({f"lbl_illum.{m}": _public_names(f"lbl_illum.{m}") for m in LAYERS + SHARED_PUBLIC})
    wrong = []
    files = sorted((ROOT / "validation").rglob("*.py"))
    assert len(files) > 10
    for path in files:
        for line, module, names in _lbl_imports(path):
            where = f"{path.relative_to(ROOT)}:{line}"
            if module not in public:
                wrong.append(f"{where} imports from {module} (not a public module)")
            elif names is None:
                wrong.append(f"{where} imports the module {module} (import names from it)")
            else:
                wrong += [f"{where} imports {module}.{n} (not in its __all__)" for n in names
                          if n not in public[module]]
    assert not wrong, "\n".join(wrong)


def test_pyproject_installs_every_package_of_the_source():
    setup = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]
    listed = set(setup["packages"])
    found = {".".join(p.parent.relative_to(ROOT).parts) for p in (ROOT / "lbl_illum").rglob("__init__.py")}
    assert found <= listed, sorted(found - listed)
    assert setup["package-dir"] == {"lbl_illum_studies": "validation/studies"}


def _install_like_a_wheel(target: Path) -> None:
    """Copy the modules of the packages pyproject.toml lists to ``target`` as a wheel lays
    them out (the studies as ``lbl_illum_studies``); only .py files, as setuptools takes."""
    setup = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]
    for package in setup["packages"]:
        source = ROOT / setup["package-dir"].get(package, package.replace(".", "/"))
        dest = target / package.replace(".", "/")
        dest.mkdir(parents=True, exist_ok=True)
        for module in source.glob("*.py"):
            shutil.copy2(module, dest / module.name)


@pytest.mark.slow
def test_the_studies_run_from_an_installed_copy(tmp_path):
    site = tmp_path / "site"
    _install_like_a_wheel(site)
    work = tmp_path / "work"
    work.mkdir()
    script = (
        "import importlib, sys\n"
        "import lbl_illum, lbl_illum_studies\n"
        f"assert lbl_illum.__file__.startswith({str(site)!r}), lbl_illum.__file__\n"
        f"assert lbl_illum_studies.__file__.startswith({str(site)!r}), lbl_illum_studies.__file__\n"
        "for module in lbl_illum_studies.STUDIES.values():\n"
        "    importlib.import_module('lbl_illum_studies.' + module)\n"
        "from lbl_illum.cli.main import main\n"
        "sys.exit(main(['validate', 'sky-component', '--quick', '--report', 'reports']))\n")
    env = {**os.environ, "PYTHONPATH": str(site), "PYTHONNOUSERSITE": "1"}
    proc = subprocess.run([sys.executable, "-c", script], cwd=work, env=env, capture_output=True, text=True,
                          timeout=300)
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert (work / "reports" / "sky-component" / "report.md").is_file()
    assert "validate sky-component (quick)" in proc.stderr
