"""The layers panel (thesis 4.1): a thumbnail per layer, visibility, rename, + and −,
duplicate, mirror, and drag to reorder depth.

The list mirrors ``doc.layers`` front-most first (the top row is in front); it is rebuilt from
the document on every layer event, so a refused edit simply shows the document again. The
panel's edits are requests (signals) that the window turns into commands.
"""

from __future__ import annotations

import threading

from PySide6.QtCore import QSize, Qt, QTimer, Signal
from PySide6.QtWidgets import (
    QAbstractItemView,
    QHBoxLayout,
    QListWidget,
    QListWidgetItem,
    QPushButton,
    QVBoxLayout,
    QWidget,
)

from sketchforge.qt.render2d import layer_thumbnail, thumbnail_pixels

#: A layer with more triangles than this gets its thumbnail shaded off the GUI thread.
THUMBNAIL_NOW_FACES = 20_000

ID_ROLE = Qt.ItemDataRole.UserRole


class LayerList(QListWidget):
    """A list whose internal drag-and-drop reports (layer id, new row) instead of moving rows."""

    row_dropped = Signal(str, int)

    def dropEvent(self, event) -> None:
        item = self.currentItem()
        target = self.itemAt(event.position().toPoint())
        if item is None:
            event.ignore()
            return
        row = self.count() - 1 if target is None else self.row(target)
        event.setDropAction(Qt.DropAction.IgnoreAction)
        event.accept()  # the document moves the layer; the list is rebuilt from it
        lid = item.data(ID_ROLE)
        QTimer.singleShot(0, lambda: self.row_dropped.emit(lid, row))


class LayersPanel(QWidget):
    add_requested = Signal()
    remove_requested = Signal(str)
    duplicate_requested = Signal(str)
    mirror_requested = Signal(str)
    visibility_requested = Signal(str, bool)
    rename_requested = Signal(str, str)
    move_requested = Signal(str, int)  # layer id, index in doc.layers (0 = back)
    current_changed = Signal(object)  # layer id or None
    #: (layer, light, shader, key, pixels) from a thumbnail's worker, to the GUI thread
    _thumbnail_ready = Signal(object, object, object, object, object)

    def __init__(self, doc, thumbnail_style, parent=None) -> None:
        super().__init__(parent)
        self.doc = doc
        self.thumbnail_style = thumbnail_style  # () -> (light, shader)
        #: {layer id: ((mesh, stroke bytes, light, shader name), icon)}: see _thumbnail
        self._thumbnails: dict = {}
        self._thumbnail_ready.connect(self._set_thumbnail)
        self.list = LayerList()
        self.list.setIconSize(QSize(48, 48))
        self.list.setDragDropMode(QAbstractItemView.DragDropMode.InternalMove)
        self.list.setDefaultDropAction(Qt.DropAction.MoveAction)
        self.list.setEditTriggers(
            QAbstractItemView.EditTrigger.DoubleClicked | QAbstractItemView.EditTrigger.EditKeyPressed
        )
        self.add = QPushButton("+")
        self.remove = QPushButton("−")
        self.duplicate = QPushButton("Duplicate")
        self.mirror = QPushButton("Mirror")
        for b, tip in (
            (self.add, "Add an empty layer in front"),
            (self.remove, "Remove the selected layer"),
            (self.duplicate, "Copy the selected layer in front of it"),
            (self.mirror, "Mirror the selected layer's stroke left-right"),
        ):
            b.setToolTip(tip)
        self.add.setFixedWidth(32)
        self.remove.setFixedWidth(32)
        buttons = QHBoxLayout()
        for b in (self.add, self.remove, self.duplicate, self.mirror):
            buttons.addWidget(b)
        lay = QVBoxLayout(self)
        lay.setContentsMargins(0, 0, 0, 0)
        lay.addWidget(self.list)
        lay.addLayout(buttons)

        self._updating = False
        self.add.clicked.connect(self.add_requested.emit)
        self.remove.clicked.connect(lambda: self._with_current(self.remove_requested))
        self.duplicate.clicked.connect(lambda: self._with_current(self.duplicate_requested))
        self.mirror.clicked.connect(lambda: self._with_current(self.mirror_requested))
        self.list.itemChanged.connect(self._item_changed)
        self.list.currentItemChanged.connect(self._current_changed)
        self.list.row_dropped.connect(self._dropped)
        for sig in (doc.layer_inserted, doc.layer_removed, doc.layer_moved, doc.layer_changed):
            sig.connect(lambda *a: self.rebuild())
        self.rebuild()

    # --- document -> list -------------------------------------------------------------------
    def current_id(self) -> str | None:
        item = self.list.currentItem()
        return None if item is None else item.data(ID_ROLE)

    def select(self, layer_id: str | None) -> None:
        for row in range(self.list.count()):
            if self.list.item(row).data(ID_ROLE) == layer_id:
                self.list.setCurrentRow(row)
                return

    def _thumbnail(self, layer, light, shader):
        """The layer's thumbnail, drawn again only when its mesh, stroke or the style changed:
        every change of the document rebuilds the list, and drawing every layer's thumbnail
        each time held the window up to 0.4 s with a 46k-vertex layer (issue 30)."""
        key = (layer.mesh, None if layer.points is None else layer.points.tobytes(), light, getattr(shader, "name", shader))
        cached = self._thumbnails.get(layer.id)
        if cached is not None and cached[0][0] is key[0] and cached[0][1:] == key[1:]:
            return cached[1]
        if layer.mesh is not None and layer.mesh.n_faces > THUMBNAIL_NOW_FACES:
            # Shaded off the GUI thread; meanwhile the old picture, or the stroke.
            icon = cached[1] if cached is not None else layer_thumbnail(layer, light, shader, placeholder=True)
            self._thumbnails[layer.id] = ((None,) + key[1:], icon)  # not final: drawn again if asked
            self._start_thumbnail(layer, light, shader, key)
            return icon
        icon = layer_thumbnail(layer, light, shader)
        self._thumbnails[layer.id] = (key, icon)
        return icon

    def _start_thumbnail(self, layer, light, shader, key) -> None:
        def work():
            try:
                rgb = thumbnail_pixels(layer, light, shader)
            except Exception:  # noqa: BLE001 - the placeholder stays; the canvas shows any error
                return
            try:
                self._thumbnail_ready.emit(layer, light, shader, key, rgb)
            except RuntimeError:  # the panel is gone
                pass

        threading.Thread(target=work, name="layer-thumbnail", daemon=True).start()

    def _set_thumbnail(self, layer, light, shader, key, rgb) -> None:
        if layer.id not in self.doc.layer_ids() or self.doc.layer(layer.id).mesh is not key[0]:
            return  # changed again meanwhile: that change drew its own
        icon = layer_thumbnail(layer, light, shader, rgb=rgb)
        self._thumbnails[layer.id] = (key, icon)
        for row in range(self.list.count()):
            item = self.list.item(row)
            if item.data(ID_ROLE) == layer.id:
                self._updating = True
                item.setIcon(icon)
                self._updating = False

    def rebuild(self) -> None:
        keep = self.current_id()
        ids = set(self.doc.layer_ids())
        self._thumbnails = {k: v for k, v in self._thumbnails.items() if k in ids}
        light, shader = self.thumbnail_style()
        self._updating = True
        try:
            self.list.clear()
            for layer in reversed(self.doc.layers):  # front-most on top
                item = QListWidgetItem(layer.name)
                item.setData(ID_ROLE, layer.id)
                item.setFlags(
                    Qt.ItemFlag.ItemIsSelectable
                    | Qt.ItemFlag.ItemIsEnabled
                    | Qt.ItemFlag.ItemIsEditable
                    | Qt.ItemFlag.ItemIsUserCheckable
                    | Qt.ItemFlag.ItemIsDragEnabled
                )
                item.setCheckState(Qt.CheckState.Checked if layer.visible else Qt.CheckState.Unchecked)
                item.setIcon(self._thumbnail(layer, light, shader))
                item.setToolTip(f"{layer.id}: {'visible' if layer.visible else 'hidden'}; double-click to rename")
                self.list.addItem(item)
        finally:
            self._updating = False
        ids = self.doc.layer_ids()
        if keep in ids:
            self.select(keep)
        elif ids:
            self.select(ids[-1])
        else:
            self.current_changed.emit(None)
        has = bool(ids)
        for b in (self.remove, self.duplicate, self.mirror):
            b.setEnabled(has)

    def refresh_thumbnails(self) -> None:
        light, shader = self.thumbnail_style()
        for row in range(self.list.count()):
            item = self.list.item(row)
            lid = item.data(ID_ROLE)
            if lid in self.doc.layer_ids():
                self._updating = True
                item.setIcon(self._thumbnail(self.doc.layer(lid), light, shader))
                self._updating = False

    # --- list -> requests -------------------------------------------------------------------
    def _with_current(self, signal) -> None:
        lid = self.current_id()
        if lid is not None:
            signal.emit(lid)

    def _item_changed(self, item) -> None:
        if self._updating:
            return
        lid = item.data(ID_ROLE)
        layer = self.doc.layer(lid)
        visible = item.checkState() == Qt.CheckState.Checked
        # Queued: the request rebuilds the list, which must not happen inside the item's signal.
        if visible != layer.visible:
            QTimer.singleShot(0, lambda: self.visibility_requested.emit(lid, visible))
        elif item.text() != layer.name:
            text = item.text()
            QTimer.singleShot(0, lambda: self.rename_requested.emit(lid, text))

    def _current_changed(self, current, previous) -> None:
        if not self._updating:
            self.current_changed.emit(None if current is None else current.data(ID_ROLE))

    def _dropped(self, layer_id: str, row: int) -> None:
        n = len(self.doc.layers)
        self.move_requested.emit(layer_id, n - 1 - row)
