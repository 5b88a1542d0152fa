"""The main window's menus and actions (File, Edit, Layer, View, Tools, Help) and the tool palette
with its shortcuts."""

from __future__ import annotations

from pathlib import Path

from PySide6.QtCore import Qt
from PySide6.QtGui import QAction, QActionGroup, QIcon, QKeySequence
from PySide6.QtWidgets import QMenu


class WindowMenus:
    """Builds the window's (``win``) menu bar, its actions and the tool palette."""

    def __init__(self, win) -> None:
        self.win = win

    def _action(self, menu, text, slot, shortcut=None, checkable=False) -> QAction:
        act = QAction(text, self.win)
        if shortcut is not None:
            if isinstance(shortcut, (list, tuple)):
                act.setShortcuts([QKeySequence(s) for s in shortcut])
            else:
                act.setShortcut(QKeySequence(shortcut))
        act.setCheckable(checkable)
        act.triggered.connect(slot)
        menu.addAction(act)
        return act

    def _build_menus(self) -> None:
        mb = self.win.menuBar()
        f = mb.addMenu("&File")
        self.win.act_new = self.win._action(f, "&New", self.win.new_document, QKeySequence.StandardKey.New)
        self.win.act_open = self.win._action(f, "&Open…", self.win.open_dialog, QKeySequence.StandardKey.Open)
        self.win.recent_menu = f.addMenu("Open &Recent")
        f.addSeparator()
        self.win.act_save = self.win._action(f, "&Save", self.win.save, QKeySequence.StandardKey.Save)
        self.win.act_save_as = self.win._action(f, "Save &As…", self.win.save_as, QKeySequence.StandardKey.SaveAs)
        self.win.act_export = self.win._action(f, "&Export…", self.win.export_dialog, "Ctrl+E")
        f.addSeparator()
        self.win._action(f, "&Quit", self.win.close, QKeySequence.StandardKey.Quit)

        e = mb.addMenu("&Edit")
        self.win.act_undo = self.win._action(e, "Undo", self.win.undo, QKeySequence.StandardKey.Undo)
        self.win.act_redo = self.win._action(e, "Redo", self.win.redo, ["Ctrl+Shift+Z", "Ctrl+Y"])
        e.addSeparator()
        self.win.act_cancel = self.win._action(e, "Cancel", self.win.cancel_current, "Esc")
        # Enter applies the strokes drawn for several picked isophotes; only while the drawing
        # has the focus (elsewhere Enter belongs to the fields).
        self.win.act_apply_strokes = self.win._action(e, "Apply sculpt strokes", self.win.apply_sculpt_strokes, ["Return", "Enter"])
        self.win.act_apply_strokes.setShortcutContext(Qt.ShortcutContext.WidgetWithChildrenShortcut)
        self.win.canvas.addAction(self.win.act_apply_strokes)

        lm = mb.addMenu("&Layer")
        self.win._action(lm, "&Add layer", self.win.add_layer, "Ctrl+Shift+N")
        self.win._action(lm, "&Remove layer", lambda: self.win._on_current(self.win.remove_layer), "Del")
        self.win._action(lm, "&Duplicate layer", lambda: self.win._on_current(self.win.duplicate_aside), "Ctrl+D")
        self.win._action(lm, "&Mirror layer", lambda: self.win._on_current(self.win.mirror_layer), "Ctrl+M")
        self.win._action(lm, "Mirror layer about its &own axis",
                     lambda: self.win._on_current(lambda i: self.win.mirror_layer(i, axis="own")), "Ctrl+Shift+M")
        lm.addSeparator()
        self.win._action(lm, "Bring &forward", lambda: self.win._on_current(lambda lid: self.win.move_depth(lid, +1)), "PgUp")
        self.win._action(lm, "Send &backward", lambda: self.win._on_current(lambda lid: self.win.move_depth(lid, -1)), "PgDown")
        self.win._action(lm, "Bring to fron&t", lambda: self.win._on_current(lambda lid: self.win.move_depth(lid, "front")), "Home")
        self.win._action(lm, "Send to bac&k", lambda: self.win._on_current(lambda lid: self.win.move_depth(lid, "back")), "End")
        lm.addSeparator()
        # Arrows move the selected part only while the drawing has the focus: elsewhere they
        # belong to the lists and fields.
        for text, key, step in (("left", "Left", (-1, 0)), ("right", "Right", (1, 0)), ("up", "Up", (0, 1)), ("down", "Down", (0, -1))):
            act = self.win._action(
                lm,
                f"Move {text}",
                lambda _=False, s=step: self.win._on_current(lambda lid: self.win.nudge(lid, s)),
                key,
            )
            act.setShortcutContext(Qt.ShortcutContext.WidgetWithChildrenShortcut)
            self.win.canvas.addAction(act)

        v = mb.addMenu("&View")
        self.win._action(v, "&Fit drawing", self.win.canvas.fit, "Ctrl+0")
        self.win._action(v, "Reference &image…", self.win.reference_dialog)
        self.win._action(v, "&Clear reference image", lambda: self.win.canvas.set_reference_image(None))
        v.addSeparator()
        self.win.act_light = self.win._action(v, "&Light tool", lambda on: self.win.modes.light.setChecked(on), "L", checkable=True)
        v.addSeparator()
        group = QActionGroup(self.win)
        for name, key in (("editing", "F2"), ("sculpture", "F3"), ("observation", "F4")):
            act = self.win._action(v, f"{name.upper()}", lambda _=False, n=name: self.win.set_mode(n), key)
            group.addAction(act)
        h = mb.addMenu("&Help")
        self.win._action(h, "&Gestures and keys", self.win.toggle_help, ["F1", "?"])
        self.win.act_plugins = self.win._action(h, "&Plugins…", self.win.show_plugins)
        self.win.update_recent_menu()

    def _build_tool_palette(self) -> None:
        """Every registered tool, in the SCULPTURE panel's palette and a Tools menu with its
        shortcut (a tool's ``shortcut`` that the window already uses is dropped, with a
        message naming the plugin)."""
        entries = self.win.sculpt.tool_entries()
        taken = {a.shortcut().toString() for a in self.win.findChildren(QAction) if not a.shortcut().isEmpty()}
        menu = QMenu("&Tools", self.win)
        help_menu = next((a for a in self.win.menuBar().actions() if a.text() == "&Help"), None)
        self.win.menuBar().insertMenu(help_menu, menu) if help_menu is not None else self.win.menuBar().addMenu(menu)
        self.win.tool_actions = {}
        usable = []
        icons = {}
        for name, label, shortcut in entries:
            cls = self.win.host.tools[name]
            icon_path = getattr(cls, "icon", "") or ""
            if icon_path and Path(icon_path).is_file():
                icons[name] = QIcon(str(icon_path))
            key = QKeySequence(shortcut).toString() if shortcut else ""
            if key and key in taken:
                who = self.win.host.provider_of(cls) if hasattr(self.win.host, "provider_of") else None
                self.win.show_message(f"tool {name!r} (plugin {who!r}): shortcut {shortcut} is already used; choose it from the Tools menu")
                key = ""
            taken.add(key)
            act = self.win._action(menu, label, lambda _=False, n=name: self.win.select_tool(n), key or None)
            if name in icons:
                act.setIcon(icons[name])
            self.win.tool_actions[name] = act
            usable.append((name, label, key))
        if not entries:
            menu.addAction("(no tool plugin installed)").setEnabled(False)
        self.win.sculpt_panel.set_tools(usable, self.win.sculpt.tool_name, icons)
