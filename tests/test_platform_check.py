"""First start on a fresh machine: the decision made before any QApplication exists, with a
fake environment and a fake library finder (no Qt is imported)."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

from sketchforge.qt.platform_check import XCB_LIBRARIES, diagnose, missing_packages

ROOT = Path(__file__).resolve().parents[1]
ALL = {lib for lib, _ in XCB_LIBRARIES}


def finder(missing=()):
    return lambda name: None if name in missing else f"lib{name}.so"


def test_a_fresh_debian_image_gets_the_missing_packages_named():
    line = diagnose({"DISPLAY": ":0"}, finder({"xcb-icccm", "xcb-keysyms"}), "linux")
    assert line.count("\n") == 0
    assert "libxcb-icccm4 libxcb-keysyms1" in line and "make deps" in line
    assert "sudo apt-get install libxcb-icccm4 libxcb-keysyms1" in line


def test_no_display_points_to_xvfb_and_the_headless_commands():
    line = diagnose({}, finder(), "linux")
    assert "no display" in line and "xvfb-run" in line and "sketchforge info" in line
    # missing libraries do not matter yet: the display is the first thing to fix
    assert diagnose({"QT_QPA_PLATFORM": "xcb"}, finder(ALL), "linux") == line


def test_nothing_to_say_when_a_window_can_open():
    assert diagnose({"DISPLAY": ":1"}, finder(), "linux") is None
    assert diagnose({"DISPLAY": ":1", "QT_QPA_PLATFORM": "xcb"}, finder(), "linux") is None
    # a platform chosen explicitly is trusted; Wayland does not need xcb
    for env in ({"QT_QPA_PLATFORM": "offscreen"}, {"QT_QPA_PLATFORM": "wayland"}, {"WAYLAND_DISPLAY": "wayland-0"}):
        assert diagnose(env, finder(ALL), "linux") is None
    assert diagnose({}, finder(ALL), "darwin") is None
    # the escape hatch for libraries the linker cache does not list
    assert diagnose({"DISPLAY": ":1", "SKETCHFORGE_NO_PLATFORM_CHECK": "1"}, finder(ALL), "linux") is None


def test_missing_packages_keeps_the_table_order():
    assert missing_packages(finder({"xkbcommon-x11", "xcb-cursor"})) == ["libxcb-cursor0", "libxkbcommon-x11-0"]
    assert missing_packages(finder()) == []


def test_make_deps_installs_exactly_the_packages_the_check_names():
    text = (ROOT / "Makefile").read_text()
    block = re.search(r"DEB_PACKAGES := (.*?)\n(?!\t)", text, re.S).group(1)
    assert block.replace("\\", " ").split() == [pkg for _, pkg in XCB_LIBRARIES]
    assert re.search(r"^deps:\n\t\$\(SUDO\) apt-get install -y --no-install-recommends \$\(DEB_PACKAGES\)", text, re.M)


def test_the_app_prints_one_line_and_exits_2_without_a_display():
    env = {"PATH": "/usr/bin:/bin", "HOME": str(ROOT)}
    out = subprocess.run([sys.executable, "-m", "sketchforge"], env=env, capture_output=True, text=True, timeout=120)
    assert out.returncode == 2
    lines = [l for l in out.stderr.splitlines() if l.strip()]
    assert len(lines) == 1 and lines[0].startswith("sketchforge: no display")
    assert "qt.qpa" not in out.stderr and "abort" not in out.stderr.lower()

