"""Packaging: desktop entry, icons, resource lookup, one version everywhere, the bundle.

The fast tests read files and run ``lps --version``; the slow one builds the
PyInstaller bundle (minutes) and runs both of its programs offscreen.
"""
from __future__ import annotations

import configparser
import os
import re
import shutil
import struct
import subprocess
import sys
from pathlib import Path

import pytest

import lps_gui
from lps_gui import resources

ROOT = Path(__file__).resolve().parent.parent
PACKAGING = ROOT / "packaging"
RESOURCES = ROOT / "resources"
BUNDLE_DIR = ROOT / "dist" / "lps-calib"
PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


def pyproject_version() -> str:
    match = re.search(r'^version\s*=\s*"([^"]+)"', (ROOT / "pyproject.toml").read_text(), re.M)
    assert match, "pyproject.toml has no version line"
    return match.group(1)


def png_size_px(path: Path) -> tuple[int, int]:
    """(width, height) from a PNG's IHDR chunk; fails on anything that is not a PNG."""
    head = path.read_bytes()[:24]
    assert head[:8] == PNG_SIGNATURE, f"{path.name} is not a PNG"
    assert head[12:16] == b"IHDR", f"{path.name} has no IHDR chunk first"
    return struct.unpack(">II", head[16:24])


def desktop_entry() -> configparser.SectionProxy:
    parser = configparser.ConfigParser(interpolation=None, strict=True)
    parser.optionxform = str  # keys are case-sensitive in desktop entries
    parser.read_string((PACKAGING / "lps-gui.desktop").read_text())
    return parser["Desktop Entry"]


def test_desktop_entry_has_the_required_keys_and_valid_values():
    entry = desktop_entry()
    for key in ("Type", "Name", "Exec", "Icon", "Categories"):
        assert entry.get(key), f"desktop entry lacks {key}"
    assert entry["Type"] == "Application"
    assert entry["Exec"].split()[0] == "lps-gui"
    assert entry["Terminal"] == "false"
    assert entry["Categories"].endswith(";"), "desktop-file-validate wants lists ending in ';'"
    assert {"Science", "Engineering"} <= set(entry["Categories"].rstrip(";").split(";"))
    # the icon is named by theme name (no path, no suffix) and the install script provides that name
    assert entry["Icon"] == Path(resources.APP_ICON_SVG).stem
    assert "lps-gui.png" in (PACKAGING / "install-desktop.sh").read_text()


def test_gui_script_name_matches_desktop_exec():
    scripts = (ROOT / "pyproject.toml").read_text().split("[project.gui-scripts]", 1)[1]
    assert re.search(r'^lps-gui\s*=\s*"lps_gui\.gui\.app:main"', scripts, re.M)
    assert desktop_entry()["Exec"].split()[0] == "lps-gui"


@pytest.mark.parametrize("size_px", resources.APP_ICON_SIZES_PX)
def test_icon_exists_in_every_size_as_a_png_of_that_size(size_px):
    path = resources.resource_path(resources.app_icon_name(size_px))
    assert png_size_px(path) == (size_px, size_px)


def test_icon_svg_is_a_square_svg_drawing():
    text = resources.resource_path(resources.APP_ICON_SVG).read_text()
    assert "<svg" in text and 'viewBox="0 0 256 256"' in text


def test_resource_path_finds_the_source_files_and_lists_all_sizes():
    assert resources.resource_path("lps-gui.svg").samefile(RESOURCES / "lps-gui.svg")
    paths = resources.app_icon_paths()
    assert [png_size_px(p)[0] for p in paths] == list(resources.APP_ICON_SIZES_PX)


def test_resource_path_prefers_the_bundle_folder(tmp_path, monkeypatch):
    (tmp_path / "resources").mkdir()
    (tmp_path / "resources" / "lps-gui.svg").write_text("<svg/>")
    monkeypatch.setattr(sys, "_MEIPASS", str(tmp_path), raising=False)
    assert resources.resource_path("lps-gui.svg") == tmp_path / "resources" / "lps-gui.svg"
    # a name only the checkout has still resolves there
    assert resources.resource_path("lps-gui-16.png").samefile(RESOURCES / "lps-gui-16.png")


def test_resource_path_names_the_folders_searched_when_missing():
    with pytest.raises(FileNotFoundError, match="no-such-file.png.*resources"):
        resources.resource_path("no-such-file.png")


def test_wheel_package_data_points_at_the_resources():
    """The wheel carries lps_gui/_resources, a symlink to the top-level folder."""
    link = ROOT / "lps_gui" / "_resources"
    assert link.is_symlink() and link.resolve() == RESOURCES.resolve()
    assert '"_resources/*"' in (ROOT / "pyproject.toml").read_text()


def test_package_version_is_the_pyproject_version():
    assert lps_gui.__version__ == pyproject_version()


def test_lps_version_prints_the_pyproject_version():
    """The installed console script, exactly as an operator types it."""
    script = Path(sys.executable).parent / "lps"
    if not script.is_file():
        pytest.skip(f"no console script next to {sys.executable}: lps-calib is not pip-installed here")
    out = subprocess.run([str(script), "--version"], capture_output=True, text=True, cwd=ROOT, timeout=60)
    assert out.returncode == 0, out.stderr
    assert out.stdout.strip() == f"lps-calib {pyproject_version()}"


def test_no_module_hard_codes_the_version():
    """One source: modules must read lps_gui.__version__, never repeat the number."""
    literal = re.compile(r"""["']""" + re.escape(pyproject_version()) + r"""["']""")
    offenders = [str(p.relative_to(ROOT)) for p in sorted((ROOT / "lps_gui").rglob("*.py"))
                 if literal.search(p.read_text(encoding="utf-8"))]
    assert not offenders, f"version literal in {offenders}; use lps_gui.__version__"


@pytest.mark.parametrize("command,expected", [("lps", "lps-calib "), ("lps-gui", "usage: lps-gui")])
def test_bundle_launcher_dispatches_on_its_own_name(tmp_path, command, expected):
    """The bundle's two executables are one script; its file name picks the program."""
    link = tmp_path / command
    link.symlink_to(PACKAGING / "launcher.py")
    args = ["--version"] if command == "lps" else ["--help"]  # neither starts Qt
    out = subprocess.run([sys.executable, str(link), *args], capture_output=True, text=True, cwd=ROOT, timeout=60)
    assert out.returncode == 0, out.stderr
    assert out.stdout.startswith(expected)


@pytest.mark.slow
@pytest.mark.timeout(1800)
def test_bundle_builds_and_both_programs_run_offscreen(tmp_path):
    """`make package`, then run the bundled `lps --version` and `lps-gui --screenshot`."""
    build = subprocess.run(["make", "package"], cwd=ROOT, capture_output=True, text=True, timeout=1700)
    assert build.returncode == 0, build.stdout[-3000:] + build.stderr[-3000:]
    env = dict(os.environ, QT_QPA_PLATFORM="offscreen")

    version = subprocess.run([str(BUNDLE_DIR / "lps"), "--version"], capture_output=True, text=True,
                             env=env, timeout=120)
    assert version.returncode == 0, version.stderr
    assert version.stdout.strip() == f"lps-calib {pyproject_version()}"
    for size_px in resources.APP_ICON_SIZES_PX:
        assert png_size_px(BUNDLE_DIR / "_internal" / "resources" / resources.app_icon_name(size_px))[0] == size_px
    qt_dir = BUNDLE_DIR / "_internal" / "PySide6" / "Qt"
    assert {p.name for p in (qt_dir / "plugins" / "platforms").iterdir()} == {"libqoffscreen.so", "libqxcb.so"}
    # everything the X11 plugin links must resolve (ldd comes with glibc, which the bundle needs anyway)
    lib_path = os.pathsep.join([str(BUNDLE_DIR / "_internal"), str(qt_dir / "lib")])
    ldd = subprocess.run(["ldd", str(qt_dir / "plugins" / "platforms" / "libqxcb.so")], capture_output=True,
                         text=True, env=dict(env, LD_LIBRARY_PATH=lib_path))
    assert "not found" not in ldd.stdout, ldd.stdout

    shot = tmp_path / "x.png"
    gui = subprocess.run([str(BUNDLE_DIR / "lps-gui"), "--screenshot", str(shot)], capture_output=True,
                         text=True, env=env, timeout=300)
    assert gui.returncode == 0, gui.stderr[-3000:]
    width_px, height_px = png_size_px(shot)
    assert width_px > 200 and height_px > 200

    if shutil.which("xvfb-run") is None:
        pytest.skip("xvfb-run is not installed: the bundle's X11 (xcb) plugin was not exercised")
    shot_xcb = tmp_path / "xcb.png"
    gui_xcb = subprocess.run(["xvfb-run", "-a", "-s", "-screen 0 1920x1200x24", str(BUNDLE_DIR / "lps-gui"),
                              "--screenshot", str(shot_xcb)], capture_output=True, text=True,
                             env=dict(env, QT_QPA_PLATFORM="xcb"), timeout=300)
    assert gui_xcb.returncode == 0, gui_xcb.stderr[-3000:]
    assert png_size_px(shot_xcb)[0] > 200
