"""The Qt bindings must not drop references to None/True/False (PySide6 6.12.0 on Python 3.11
does, and the interpreter aborts after a few hundred bool signals)."""

import subprocess
import sys

PROBE = """
import sys
from PySide6.QtCore import QObject, QPointF, Signal
class P(QObject):
    flag = Signal(bool)
p = P(); p.flag.connect(lambda v: None); pt = QPointF()
a = sys.getrefcount(None); [pt.setX(1.0) for _ in range(200)]; b = sys.getrefcount(None)
c = sys.getrefcount(True); [p.flag.emit(True) for _ in range(50)]; d = sys.getrefcount(True)
print(b - a, d - c)
"""


def test_bindings_keep_singleton_references():
    res = subprocess.run([sys.executable, "-c", PROBE], capture_output=True, text=True, timeout=120)
    assert res.returncode == 0, res.stderr[-500:]
    none_delta, bool_delta = map(int, res.stdout.split())
    # A leaking binding loses one reference per call (-200 / -50); allow a few for the
    # interpreter's own temporaries.
    assert none_delta > -20 and bool_delta > -10, (none_delta, bool_delta)
