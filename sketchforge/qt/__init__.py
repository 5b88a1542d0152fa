"""The desktop app (PySide6 + pyqtgraph). Nothing outside this package imports it.

PySide6 6.12.0 on Python 3.11 drops references to ``None`` and ``True``/``False`` and aborts
the interpreter after enough calls; pyproject pins ``pyside6-essentials<6.12`` and
``tests/qt/test_bindings.py`` checks the installed bindings do not leak.
"""
