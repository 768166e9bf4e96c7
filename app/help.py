"""Help that teaches: The model, Reading the plots, Comparing methods (HTML pages shipped with the app) and the
keyboard shortcuts, generated from the window's actions so the list cannot go stale.

Widgets name a help topic (``set_topic``); their tooltip then says where to read more, and F1
over them opens the help there.
"""

from __future__ import annotations

import html
from PySide6 import QtCore, QtGui, QtWidgets

from rollball import resources

PAGES = {"model.html": "The model", "plots.html": "Reading the plots", "compare.html": "Comparing methods",
         "keys": "Keyboard shortcuts"}
TOPIC = "helpTopic"   # widget property holding a topic such as "model.html#liftoff"


def page_html(name: str) -> str:
    return resources.path("help_pages", name).read_text(encoding="utf-8")


def set_topic(widget: QtWidgets.QWidget, topic: str) -> None:
    """Link a widget to a help topic: its tooltip says so, and F1 over it opens the page there."""
    page = PAGES[topic.partition("#")[0]]
    widget.setProperty(TOPIC, topic)
    tip = widget.toolTip()
    widget.setToolTip(f"{tip}<br><i>F1: Help → {page}</i>" if tip else f"<i>F1: Help → {page}</i>")


def topic_at(widget: QtWidgets.QWidget | None) -> str | None:
    """The help topic of a widget or the nearest of its parents that has one."""
    while widget is not None:
        topic = widget.property(TOPIC)
        if topic:
            return topic
        widget = widget.parentWidget()
    return None


def shortcuts_html(actions) -> str:
    """A table of every action that has a shortcut, in the order given (menus' order)."""
    rows, seen = [], set()
    for action in actions:
        keys = [k.toString(QtGui.QKeySequence.SequenceFormat.NativeText) for k in action.shortcuts()]
        keys = [k for k in keys if k]
        if not keys or id(action) in seen:
            continue
        seen.add(id(action))
        name = action.text().replace("&", "").rstrip("…")
        rows.append(f"<tr><td><b>{html.escape(' or '.join(keys))}</b></td><td>{html.escape(name)}</td>"
                    f"<td style='color:#555'>{html.escape(action.statusTip())}</td></tr>")
    return ("<html><body><h1>Keyboard shortcuts</h1><p>Taken from the window's menus and keys as they are now.</p>"
            "<table cellpadding='4'>" + "".join(rows) + "</table>"
            "<p>F1 over a readout, a plot or a field opens the help where it is explained.</p></body></html>")


class HelpWindow(QtWidgets.QWidget):
    """A small browser over the help pages, with the pages listed on the left."""

    def __init__(self, actions, parent=None):
        super().__init__(parent, QtCore.Qt.WindowType.Window)
        self.setWindowTitle("RollBall Help")
        self.setObjectName("help")
        self.actions_source = actions       # callable giving the window's actions, read when shown
        self.pages = QtWidgets.QListWidget(objectName="help.pages")
        for name, title in PAGES.items():
            item = QtWidgets.QListWidgetItem(title)
            item.setData(QtCore.Qt.ItemDataRole.UserRole, name)
            self.pages.addItem(item)
        self.pages.setFixedWidth(170)
        self.browser = QtWidgets.QTextBrowser(objectName="help.browser")
        self.browser.setOpenLinks(False)
        self.browser.anchorClicked.connect(self._link)
        layout = QtWidgets.QHBoxLayout(self)
        layout.addWidget(self.pages)
        layout.addWidget(self.browser, 1)
        self.pages.currentRowChanged.connect(lambda row: self.show_topic(list(PAGES)[row]))
        self.page = ""
        self.resize(860, 680)

    def show_topic(self, topic: str) -> None:
        """Show a page (``model.html``, ``plots.html``, ``compare.html`` or ``keys``), scrolled to
        ``#anchor`` if given."""
        name, _, anchor = topic.partition("#")
        if name != self.page:
            self.page = name
            self.browser.setHtml(shortcuts_html(self.actions_source()) if name == "keys" else page_html(name))
            self.pages.blockSignals(True)
            self.pages.setCurrentRow(list(PAGES).index(name))
            self.pages.blockSignals(False)
        if anchor:
            self.browser.scrollToAnchor(anchor)
        else:
            self.browser.verticalScrollBar().setValue(0)
        self.show()
        self.raise_()
        self.activateWindow()

    def _link(self, url: QtCore.QUrl) -> None:
        if url.scheme() in ("http", "https"):
            QtGui.QDesktopServices.openUrl(url)
            return
        target = url.toString()
        self.show_topic(target if target.partition("#")[0] in PAGES else f"{self.page}{target}")
