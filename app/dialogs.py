"""The options dialogs of Save Image and Export Animation: a file, and how to draw it."""

from __future__ import annotations

from pathlib import Path

from PySide6 import QtCore, QtWidgets

from .formats import DEFAULT_FPS, FORMATS, MAX_FPS

IMAGE_SCALES = (("1× (as on screen)", 1), ("2×", 2), ("4× (print)", 4))
ANIMATION_FILTER = ";;".join(f"{words} (*{suffix})" for suffix, words in FORMATS.items())
MAX_SIDE = 4096
VIDEO_PRESETS = (("720p (1280×720)", (1280, 720)), ("1080p (1920×1080)", (1920, 1080)))   # besides the view's size


class _FileDialog(QtWidgets.QDialog):
    """A file row (text and Browse…) above a form of options, OK and Cancel."""

    def __init__(self, title: str, path: Path, file_filter: str, parent=None):
        super().__init__(parent)
        self.setWindowTitle(title)
        self.file_filter = file_filter
        self.path_edit = QtWidgets.QLineEdit(str(path), objectName="path")
        browse = QtWidgets.QPushButton("Browse…")
        browse.clicked.connect(self._browse)
        row = QtWidgets.QHBoxLayout()
        row.addWidget(self.path_edit, 1)
        row.addWidget(browse)
        self.form = QtWidgets.QFormLayout()
        self.form.addRow("File", row)
        buttons = QtWidgets.QDialogButtonBox(QtWidgets.QDialogButtonBox.StandardButton.Ok
                                             | QtWidgets.QDialogButtonBox.StandardButton.Cancel)
        buttons.accepted.connect(self.accept)
        buttons.rejected.connect(self.reject)
        layout = QtWidgets.QVBoxLayout(self)
        layout.addLayout(self.form)
        layout.addWidget(buttons)

    def _browse(self) -> None:
        path, _ = QtWidgets.QFileDialog.getSaveFileName(self, self.windowTitle(), self.path_edit.text(),
                                                        self.file_filter)
        if path:
            self.path_edit.setText(path)

    @property
    def path(self) -> Path:
        return Path(self.path_edit.text().strip())


def _spin(value: float, low: float, high: float, decimals: int = 0, suffix: str = ""):
    box = QtWidgets.QDoubleSpinBox(decimals=decimals) if decimals else QtWidgets.QSpinBox()
    box.setRange(low, high)
    box.setValue(value)
    box.setSuffix(suffix)
    return box


class ImageDialog(_FileDialog):
    """Resolution, caption and plots of a saved image."""

    def __init__(self, path: Path, parent=None):
        super().__init__("Save image", path, "PNG images (*.png)", parent)
        self.scale = QtWidgets.QComboBox(objectName="imageScale")
        for label, value in IMAGE_SCALES:
            self.scale.addItem(label, value)
        self.caption = QtWidgets.QCheckBox("Caption: formula, method, step and time", objectName="imageCaption")
        self.plots = QtWidgets.QCheckBox("The plots below the view", objectName="imagePlots")
        self.form.addRow("Resolution", self.scale)
        self.form.addRow("", self.caption)
        self.form.addRow("", self.plots)

    def options(self) -> dict:
        return {"scale": self.scale.currentData(), "caption": self.caption.isChecked(),
                "plots": self.plots.isChecked()}


class AnimationDialog(_FileDialog):
    """Size, frames per second, time span and caption of an exported animation."""

    def __init__(self, path: Path, size: tuple[int, int], t_end: float, parent=None):
        super().__init__("Export animation", path, ANIMATION_FILTER, parent)
        self.width = _spin(size[0], 16, MAX_SIDE, suffix=" px")
        self.height = _spin(size[1], 16, MAX_SIDE, suffix=" px")
        self.presets = QtWidgets.QComboBox(objectName="sizePresets")
        for label, (w, h) in ((f"The view ({size[0]}×{size[1]})", size), *VIDEO_PRESETS):
            self.presets.addItem(label, (w, h))
        self.presets.addItem("Custom", None)
        self.presets.activated.connect(self._preset_chosen)
        sizes = QtWidgets.QHBoxLayout()
        sizes.addWidget(self.presets)
        sizes.addWidget(self.width)
        sizes.addWidget(QtWidgets.QLabel("×"))
        sizes.addWidget(self.height)
        self.fps = _spin(DEFAULT_FPS, 1, MAX_FPS, suffix=" per simulated second")
        self.fps.setToolTip("Frames per second of simulated time; the video plays them at that rate, "
                            "so it runs in real time")
        self.start = _spin(0.0, 0.0, t_end, decimals=3, suffix=" s")
        self.end = _spin(t_end, 0.0, t_end, decimals=3, suffix=" s")
        self.caption = QtWidgets.QCheckBox("Caption: formula, method, step and time", checked=True)
        self.form.addRow("Size", sizes)
        self.form.addRow("Frames", self.fps)
        self.form.addRow("From", self.start)
        self.form.addRow("To", self.end)
        self.form.addRow("", self.caption)

        for spin in (self.width, self.height):
            spin.valueChanged.connect(self._size_typed)

    def _preset_chosen(self, index: int) -> None:
        size = self.presets.itemData(index)
        if size is not None:
            with QtCore.QSignalBlocker(self.width), QtCore.QSignalBlocker(self.height):
                self.width.setValue(size[0])
                self.height.setValue(size[1])

    def _size_typed(self) -> None:
        """A size typed in: the preset that has it, else Custom."""
        typed = (self.width.value(), self.height.value())
        match = next((i for i in range(self.presets.count()) if self.presets.itemData(i) == typed),
                     self.presets.count() - 1)
        self.presets.setCurrentIndex(match)

    def options(self) -> dict:
        return {"size": (self.width.value(), self.height.value()), "fps": self.fps.value(),
                "t0": self.start.value(), "t1": self.end.value(), "caption": self.caption.isChecked()}
