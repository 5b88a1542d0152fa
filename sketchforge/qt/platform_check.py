"""Before the first QApplication: can Qt open a window here? If not, say why in one line.

Qt's own failure on a fresh Debian image is an abort ("qt.qpa.plugin: Could not load the Qt
platform plugin "xcb" ... This application failed to start") that names no package. So the app
checks first, with no Qt import: which platform Qt will use (``QT_QPA_PLATFORM``, else xcb on
X11 or Wayland's own plugin), whether a display is there, and whether the shared libraries the
xcb plugin links to can be found (``ctypes.util.find_library``, which reads the ld cache). The
decision (:func:`diagnose`) takes the environment and the library finder as arguments, so it is
tested with fakes.
"""

from __future__ import annotations

import ctypes.util
import os
import sys
from collections.abc import Callable, Mapping

#: Libraries Qt 6's xcb platform plugin (and libQt6XcbQpa) loads, as ``find_library`` names
#: them, with the Debian package that ships each (read off ``ldd libqxcb.so``; the xcb-util
#: ones are what a minimal image lacks).
XCB_LIBRARIES: tuple[tuple[str, str], ...] = (
    ("xcb", "libxcb1"),
    ("X11-xcb", "libx11-xcb1"),
    ("xcb-icccm", "libxcb-icccm4"),
    ("xcb-keysyms", "libxcb-keysyms1"),
    ("xcb-image", "libxcb-image0"),
    ("xcb-render-util", "libxcb-render-util0"),
    ("xcb-cursor", "libxcb-cursor0"),
    ("xcb-randr", "libxcb-randr0"),
    ("xcb-render", "libxcb-render0"),
    ("xcb-shape", "libxcb-shape0"),
    ("xcb-shm", "libxcb-shm0"),
    ("xcb-sync", "libxcb-sync1"),
    ("xcb-util", "libxcb-util1"),
    ("xcb-xfixes", "libxcb-xfixes0"),
    ("xcb-xkb", "libxcb-xkb1"),
    ("xkbcommon", "libxkbcommon0"),
    ("xkbcommon-x11", "libxkbcommon-x11-0"),
    ("EGL", "libegl1"),
    ("GL", "libgl1"),
    ("fontconfig", "libfontconfig1"),
    ("dbus-1", "libdbus-1-3"),
)

#: The headless commands a person without a display can use instead.
HEADLESS_HINT = ("`sketchforge info DOC`, `sketchforge render DOC --png OUT.png` and "
                 "`sketchforge replay DOC --export OUT.obj` work without one")


def missing_packages(find_library: Callable[[str], str | None] = ctypes.util.find_library) -> list[str]:
    """Debian packages whose xcb-plugin libraries ``find_library`` cannot find, in table order."""
    return [pkg for lib, pkg in XCB_LIBRARIES if not find_library(lib)]


def diagnose(
    env: Mapping[str, str] | None = None,
    find_library: Callable[[str], str | None] = ctypes.util.find_library,
    platform: str = sys.platform,
) -> str | None:
    """None when Qt can be expected to open a window, else the one line to print instead.

    Only Linux is checked (elsewhere Qt ships what it needs). A platform chosen explicitly
    other than xcb (offscreen, minimal, wayland, vnc...) is trusted as it is: the person asked
    for it. Without ``QT_QPA_PLATFORM`` Qt takes Wayland when ``WAYLAND_DISPLAY`` is set (and
    falls back to xcb), else xcb, which needs ``DISPLAY`` and the libraries in
    :data:`XCB_LIBRARIES`. ``SKETCHFORGE_NO_PLATFORM_CHECK=1`` skips the check (libraries
    found by some other means than the linker cache)."""
    env = os.environ if env is None else env
    if not platform.startswith("linux") or env.get("SKETCHFORGE_NO_PLATFORM_CHECK"):
        return None
    chosen = env.get("QT_QPA_PLATFORM", "").split(":", 1)[0].strip().lower()
    if chosen and chosen != "xcb":
        return None
    if not chosen and env.get("WAYLAND_DISPLAY"):
        return None
    if not env.get("DISPLAY"):
        return (
            "sketchforge: no display (DISPLAY is not set), so no window can open; run it under a virtual "
            "display with `xvfb-run -a sketchforge DOC`, use QT_QPA_PLATFORM=offscreen with --screenshot, "
            f"or the headless commands: {HEADLESS_HINT}"
        )
    missing = missing_packages(find_library)
    if missing:
        return (
            f"sketchforge: Qt's xcb window plugin needs libraries this system lacks; install the Debian "
            f"package{'s' * (len(missing) != 1)} {' '.join(missing)} (`make deps` does it: "
            f"sudo apt-get install {' '.join(missing)}; SKETCHFORGE_NO_PLATFORM_CHECK=1 skips this check)"
        )
    return None


def check_or_exit(stream=None) -> None:
    """Print :func:`diagnose`'s line and exit with status 2 when no window can open."""
    line = diagnose()
    if line is not None:
        print(line, file=stream or sys.stderr)
        raise SystemExit(2)


if __name__ == "__main__":  # `make run` asks first, so that make ends on this line, not Qt's
    _line = diagnose()
    if _line is not None:
        print(_line)
        raise SystemExit(2)
