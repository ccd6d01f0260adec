"""The wheel installs everything under one name, `mavconform`, and lives beside any project.

Issue 12: installed as top-level `fuzz`, `reports`, `conformance`... packages, the tool broke
every user project with a package of the same name (pytest could not load our plugins, exit 3).
"""

from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
import textwrap
import venv
import zipfile
from pathlib import Path

import pytest

try:
    import tomllib
except ModuleNotFoundError:  # Python 3.10
    import tomli as tomllib

ROOT = Path(__file__).resolve().parents[1]
MAPPED = ("conformance", "fuzz", "reference_impl", "reports", "vectors")


def _pyproject() -> dict:
    return tomllib.loads((ROOT / "pyproject.toml").read_text())


def _data_folders() -> set[str]:
    """The committed folders under the mapped trees that hold no Python: setuptools treats
    each as a package, so each must be listed (else a "Package would be ignored" warning)."""
    listed = subprocess.run(["git", "ls-files", "-z", *MAPPED], cwd=ROOT, capture_output=True, text=True)
    if listed.returncode != 0:
        pytest.skip("not a git checkout: the committed folders are unknown")
    folders = set()
    for name in filter(None, listed.stdout.split("\0")):
        for parent in Path(name).parents:
            if parent != Path(".") and not (ROOT / parent / "__init__.py").is_file():
                folders.add("mavconform." + ".".join(parent.parts))
    return folders


def test_every_package_and_data_folder_in_the_tree_is_listed_under_the_namespace() -> None:
    tree = {"mavconform"} | {
        "mavconform." + ".".join(init.parent.relative_to(ROOT).parts)
        for top in MAPPED for init in (ROOT / top).rglob("__init__.py")}
    tree |= {".".join(init.parent.relative_to(ROOT).parts) for init in (ROOT / "mavconform").rglob("__init__.py")}
    setuptools = _pyproject()["tool"]["setuptools"]
    assert set(setuptools["packages"]) == tree | _data_folders()
    assert setuptools["package-dir"] == {f"mavconform.{top}": top for top in MAPPED}


def _not_sources(folder: str, names: list[str]) -> list[str]:
    """Caches, and the run outputs `make` writes under reports/ (git-ignored)."""
    outputs = {"out", "fuzz", "px4", "ardupilot", "mavsdk"} if Path(folder) == ROOT / "reports" else set()
    return [n for n in names if n == "__pycache__" or n in outputs]


@pytest.fixture(scope="module")
def wheel(tmp_path_factory: pytest.TempPathFactory) -> Path:
    # Built from a copy: setuptools builds in the source tree, and a stale build/ could hide a
    # module the mapping misses.
    source, out = tmp_path_factory.mktemp("source"), tmp_path_factory.mktemp("wheel")
    for name in ("pyproject.toml", "README.md"):
        shutil.copy(ROOT / name, source / name)
    for top in ("mavconform", *MAPPED):
        shutil.copytree(ROOT / top, source / top, ignore=_not_sources)
    built = subprocess.run([sys.executable, "-m", "pip", "wheel", "--quiet", "--no-deps", "-w", str(out), str(source)],
                           capture_output=True, text=True, timeout=300)
    assert built.returncode == 0, built.stderr
    (path,) = out.glob("mavconform-*.whl")
    BUILD_OUTPUT[path] = built.stdout + built.stderr
    return path


BUILD_OUTPUT: dict[Path, str] = {}


def test_the_wheel_builds_without_a_warning(wheel: Path) -> None:
    """Issue 29: eight "Package would be ignored" warnings (440 lines) before a fresh clone's
    first run; the data folders are now packages of their own with their files as package data."""
    said = BUILD_OUTPUT[wheel]
    assert "Warning" not in said and "would be ignored" not in said, said[:2000]


def test_the_editable_install_make_runs_prints_no_warning(tmp_path: Path) -> None:
    """Issue 29: `make run`'s set-up (the Makefile's own pip command, with its warning filter)
    prints nothing but pip's progress: setuptools' editable-install notice read as a fault."""
    makefile = (ROOT / "Makefile").read_text()
    quiet = re.search(r'^QUIET_EDITABLE = (\w+)="([^"]*)"$', makefile, re.M)
    assert quiet and "$(QUIET_EDITABLE) $(BIN)/python -m pip install --quiet -e ." in makefile
    source = tmp_path / "source"
    source.mkdir()
    for name in ("pyproject.toml", "README.md"):
        shutil.copy(ROOT / name, source / name)
    for top in ("mavconform", *MAPPED):
        shutil.copytree(ROOT / top, source / top, ignore=_not_sources)
    venv.create(tmp_path / "venv", with_pip=False)
    env = {**os.environ, quiet.group(1): quiet.group(2)}
    done = subprocess.run([sys.executable, "-m", "pip", "--python", str(tmp_path / "venv" / "bin" / "python"),
                           "install", "--quiet", "--no-deps", "-e", str(source)],
                          capture_output=True, text=True, timeout=300, env=env)
    said = done.stdout + done.stderr
    assert done.returncode == 0, said[:2000]
    assert "Warning" not in said and "Editable installation" not in said, said[:2000]


def test_every_data_file_the_code_reads_is_in_the_wheel(wheel: Path) -> None:
    listed = subprocess.run(["git", "ls-files", *MAPPED], cwd=ROOT, capture_output=True, text=True)
    if listed.returncode != 0:
        pytest.skip("not a git checkout")
    data = {n for n in listed.stdout.split() if not n.endswith(".py") and Path(n).name != ".gitignore"}
    with zipfile.ZipFile(wheel) as archive:
        names = set(archive.namelist())
    assert {f"mavconform/{n}" for n in data} - names == set()


def test_the_wheel_holds_one_top_level_name(wheel: Path) -> None:
    with zipfile.ZipFile(wheel) as archive:
        names = archive.namelist()
        entry_points = next(archive.read(n).decode() for n in names if n.endswith(".dist-info/entry_points.txt"))
    assert {n.split("/")[0] for n in names} == {"mavconform", "mavconform-0.1.0.dist-info"}
    assert "mavconform/conformance/expectations/px4.toml" in names
    assert "mavconform/reference_impl/profiles/px4.toml" in names
    assert "mavconform.conformance.pytest_plugin" in entry_points
    assert "mavconform.fuzz.pytest_plugin" in entry_points


def test_the_wheel_in_a_fresh_venv_beside_a_project_with_its_own_fuzz_and_reports(
        wheel: Path, tmp_path: Path) -> None:
    fresh = tmp_path / "venv"
    venv.EnvBuilder(with_pip=False).create(fresh)
    python = fresh / "bin" / "python"
    site = Path(subprocess.run([str(python), "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"],
                               capture_output=True, text=True, check=True).stdout.strip())
    installed = subprocess.run([sys.executable, "-m", "pip", "--python", str(python), "install", "--quiet",
                                "--no-deps", str(wheel)], capture_output=True, text=True, timeout=300)
    assert installed.returncode == 0, installed.stderr
    assert {p.name for p in site.iterdir()} == {"mavconform", "mavconform-0.1.0.dist-info"}
    # The dependencies (pytest, hypothesis, pymavlink, mcap) come from this interpreter's
    # site-packages folders: path lines, so their .pth files (our editable install) are not run.
    (site / "deps.pth").write_text("".join(f"{p}\n" for p in sys.path if Path(p).name in ("site-packages",
                                                                                       "dist-packages")))

    project = tmp_path / "project"
    for package, text in [("fuzz", "OWNER = 'the user'\n"), ("reports", "OWNER = 'the user'\n")]:
        (project / package).mkdir(parents=True)
        (project / package / "__init__.py").write_text(text)
    (project / "tests").mkdir()
    (project / "tests" / "test_mine.py").write_text(textwrap.dedent("""\
        import fuzz, reports

        def test_my_packages_are_mine():
            assert fuzz.OWNER == reports.OWNER == 'the user'
        """))

    def run(*args: str) -> subprocess.CompletedProcess[str]:
        return subprocess.run([str(python), *args], cwd=project, capture_output=True, text=True, timeout=300,
                              env={"PATH": "/usr/bin:/bin", "PYTHONPATH": str(project), "PYTHONDONTWRITEBYTECODE": "1"})

    mine = run("-m", "pytest", "-q", "-p", "no:cacheprovider", "tests")
    assert mine.returncode == 0, mine.stdout + mine.stderr
    assert "1 passed" in mine.stdout
    ours = run("-m", "pytest", "-q", "-p", "no:cacheprovider", "--pyargs", "mavconform.conformance",
               "--mavlink-target", "builtin:spec", "--mavlink-clauses", "MIS.UP.01",
               "--mavlink-report-dir", str(tmp_path / "r"))
    assert ours.returncode == 0, ours.stdout + ours.stderr
    assert (tmp_path / "r" / "run.json").is_file()
    clauses = run(str(fresh / "bin" / "mavconform"), "clauses", "--clauses", "MIS.UP.01")
    assert clauses.returncode == 0 and clauses.stdout.startswith("MIS.UP.01"), clauses.stdout + clauses.stderr
    where = run("-c", "import mavconform.fuzz, fuzz; print(mavconform.fuzz.__file__); print(fuzz.__file__)")
    ours_at, theirs_at = where.stdout.split()
    assert ours_at.startswith(str(site)) and theirs_at.startswith(str(project))
