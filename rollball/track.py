"""A measured track: the times and positions of a real ball, read from a table (docs/design.md §10).

A track is what video tracking (Tracker and similar tools) or a logger gives: one row per frame,
a time ``t`` and two or three of the scene's axes ``x``, ``y``, ``z``. ``Track.load`` reads CSV or
TSV with a header naming the columns (units in the header, ``x (cm)`` or ``x [cm]``, or given as
options), also the table Tracker exports (a title line above the header), and maps the file's
columns to the scene's axes (a side view's ``x`` and ``y`` are the scene's ``x`` and ``z``).
Frames where the ball was not found (an empty cell or NaN) are skipped and counted; anything
else a file cannot mean is refused with one line naming the row and the column.
"""

from __future__ import annotations

import csv
import io
import math
import os
import re
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .files import atomic_write_text, open_regular
from .fit_options import LENGTH_UNITS, TIME_UNITS
from .text import shown

AXES = ("x", "y", "z")                      # the scene's axes a track can measure
MAX_BYTES = 200_000_000                     # a larger file is refused before it is read
TITLE_LINES = 2                             # lines above the header that may be a title (Tracker's)
MISSING = {"", "nan", "NaN", "NAN"}         # a frame where the ball was not found
_HEADER = re.compile(r"^\s*([A-Za-z_][A-Za-z0-9_]*)\s*(?:[(\[]\s*([A-Za-z]+)\s*[)\]])?\s*$")


class TrackError(ValueError):
    """A track file that cannot be read: the message is one line (the file, row and column)."""


@dataclass(frozen=True, eq=False)
class Track:
    """Measured positions of the ball's centre (or contact point) in the scene's frame.

    ``t``: (n,) seconds, strictly increasing, on the scene's clock (t = 0 is its start);
    ``axes``: the scene axes measured, e.g. ("x", "z") for a side view; ``positions``: (n, len(axes))
    metres; ``skipped``: the file's rows without a position (frames where the ball was not found).
    """

    t: np.ndarray
    axes: tuple[str, ...]
    positions: np.ndarray
    skipped: int = 0
    source: str = field(default="", compare=False)

    def __post_init__(self):
        t = np.array(self.t, dtype=float, ndmin=1)
        positions = np.array(self.positions, dtype=float, ndmin=2)
        axes = tuple(self.axes)
        if not axes or len(set(axes)) != len(axes) or not set(axes) <= set(AXES):
            raise TrackError(f"a track measures two or three different axes of x, y, z, not {axes}")
        if t.ndim != 1 or positions.shape != (len(t), len(axes)):
            raise TrackError(f"a track's positions are one row of {len(axes)} per time: "
                             f"{len(t)} times, positions of shape {positions.shape}")
        if len(t) < 2:
            raise TrackError(f"a track needs at least 2 positions, not {len(t)}")
        if not (np.all(np.isfinite(t)) and np.all(np.isfinite(positions))):
            raise TrackError("a track's times and positions must be finite numbers")
        if t[0] < 0:
            raise TrackError(f"a track's times are on the scene's clock, from 0: the first is {t[0]:g} s")
        if np.any(np.diff(t) <= 0):
            i = int(np.argmax(np.diff(t) <= 0))
            raise TrackError(f"a track's times must increase: {t[i + 1]:g} s follows {t[i]:g} s")
        t.setflags(write=False)
        positions.setflags(write=False)
        object.__setattr__(self, "t", t)
        object.__setattr__(self, "positions", positions)
        object.__setattr__(self, "axes", axes)

    def __len__(self) -> int:
        return len(self.t)

    @classmethod
    def load(cls, path: str | os.PathLike, *, columns: dict[str, str] | None = None,
             length_unit: str | None = None, time_unit: str | None = None) -> Track:
        """Read a track from a CSV or TSV file (the delimiter is detected: comma, tab or semicolon).

        ``columns`` maps scene axes to the file's column names, e.g. ``{"x": "x", "z": "y"}`` for a
        side view; by default the columns named x, y, z are those axes (two or three of them) and
        ``t`` is the time. ``length_unit`` (m, cm, mm) and ``time_unit`` (s, ms) apply to columns
        whose header names no unit (``x (cm)``, ``t [ms]``); a header's unit that contradicts them
        is refused. Lines starting with ``#`` are comments; up to two lines above the header that do
        not name the columns are titles (Tracker's export puts the track's name there).
        Raises ``TrackError`` (one line: which row, which column) and ``OSError``.
        """
        name = shown(str(path))
        with open_regular(path) as stream:
            data = stream.read(MAX_BYTES + 1)
        if len(data) > MAX_BYTES:
            raise TrackError(f"{name}: larger than {MAX_BYTES // 1_000_000} MB; not a track")
        try:
            text = data.decode("utf-8-sig")
        except UnicodeDecodeError as e:
            raise TrackError(f"{name}: not a text file (byte {e.start} is not UTF-8)") from None
        return cls._parse(text, name, columns, length_unit, time_unit)

    @classmethod
    def _parse(cls, text, name, columns, length_unit, time_unit) -> Track:
        _check_unit(length_unit, LENGTH_UNITS, "length", name)
        _check_unit(time_unit, TIME_UNITS, "time", name)
        lines = [(number, line) for number, line in enumerate(text.splitlines(), 1)
                 if line.strip() and not line.lstrip().startswith("#")]
        if not lines:
            raise TrackError(f"{name}: empty (no header, no rows)")
        delimiter = _delimiter(lines[0][1] if len(lines) == 1 else lines[min(len(lines) - 1, TITLE_LINES)][1])
        rows = list(csv.reader(io.StringIO("\n".join(line for _, line in lines)), delimiter=delimiter))
        header_at, header = _find_header(rows, name, columns)
        wanted = _wanted_columns(header, columns, name)   # axis or "t" -> (index, unit in header)
        scale = {}
        for key, (index, unit) in wanted.items():
            units, given, kind = ((TIME_UNITS, time_unit, "time") if key == "t"
                                  else (LENGTH_UNITS, length_unit, "length"))
            if unit is not None and unit not in units:
                raise TrackError(f"{name}: column {shown(header[index][0])}: unknown {kind} unit {shown(unit)} "
                                 f"(known: {', '.join(units)})")
            if unit is not None and given is not None and unit != given:
                raise TrackError(f"{name}: column {shown(header[index][0])} is in {unit}, "
                                 f"but the {kind} unit given is {given}")
            scale[key] = units[unit or given or next(iter(units))]
        axes = tuple(axis for axis in AXES if axis in wanted)
        order = ["t", *axes]
        values, skipped = [], 0
        for row_index in range(header_at + 1, len(rows)):
            row, number = rows[row_index], lines[row_index][0]
            cells = []
            for key in order:
                index = wanted[key][0]
                cell = row[index].strip() if index < len(row) else ""
                cells.append(_number(cell, name, number, header[index][0]))
            if any(math.isnan(v) for v in cells):
                if math.isnan(cells[0]):
                    raise TrackError(f"{name}: line {number}: column {shown(header[wanted['t'][0]][0])}: "
                                     f"no time (every row needs one)")
                skipped += 1
                continue
            values.append((number, cells))
        if len(values) < 2:
            raise TrackError(f"{name}: {len(values)} rows with a position ({skipped} without); a track needs 2 or more")
        table = np.array([cells for _, cells in values]) * np.array([scale[key] for key in order])
        for i in range(1, len(table)):
            if not table[i, 0] > table[i - 1, 0]:
                raise TrackError(f"{name}: line {values[i][0]}: column {shown(header[wanted['t'][0]][0])}: "
                                 f"the time {table[i, 0]:g} s does not follow {table[i - 1, 0]:g} s "
                                 f"(times must increase)")
        if table[0, 0] < 0:
            raise TrackError(f"{name}: line {values[0][0]}: the time {table[0, 0]:g} s is before the scene's "
                             f"start (times are on the scene's clock, from 0)")
        return cls(table[:, 0], axes, table[:, 1:], skipped, name)

    def noise(self) -> float:
        """The track's noise (m, one coordinate's standard deviation), estimated from the track
        alone: from its fourth differences, which take out a smooth path (what is left of it is
        h⁴ times the fourth derivative: 10⁻⁷ m for 60 frames a second and 1 m/s⁴) and leave
        white noise of variance 70 σ² (taken where five positions are evenly spaced). The differences
        more than 4 robust standard deviations
        (1.4826 times the median absolute deviation) out, across a bounce or a change of mode,
        are left out, and σ is the root mean square of the others over √70."""
        if len(self) < 8:
            raise TrackError(f"a track of {len(self)} positions is too short to estimate its noise "
                             f"(8 or more needed); give the noise")
        steps = np.diff(self.t)
        windows = np.lib.stride_tricks.sliding_window_view(steps, 4)
        even = windows.max(axis=1) <= windows.min(axis=1) * 1.01   # (a lost frame makes a gap)
        d4 = np.diff(self.positions, n=4, axis=0)[even]
        if len(d4) < 4:
            raise TrackError("too few evenly spaced positions to estimate the track's noise; give the noise")
        spread = 1.4826 * np.median(np.abs(d4 - np.median(d4, axis=0)), axis=0)
        inside = np.abs(d4) <= 4 * spread            # (a bounce's differences are far outside)
        per_axis = np.sqrt(np.sum(np.where(inside, d4, 0.0) ** 2, axis=0) / np.maximum(inside.sum(axis=0), 1) / 70)
        return float(np.sqrt(np.mean(per_axis ** 2)))

    def to_text(self, comments: tuple[str, ...] = ()) -> str:
        """The track as a CSV file ``Track.load`` reads back: ``#`` lines, a header with units
        (``t (s)``, metres), one row per position at full precision."""
        head = [f"# {line}" for line in comments]
        head.append(",".join(["t (s)", *(f"{axis} (m)" for axis in self.axes)]))
        body = (",".join(repr(float(v)) for v in (t, *p)) for t, p in zip(self.t, self.positions))
        return "\n".join([*head, *body]) + "\n"

    def save(self, path: str | os.PathLike, comments: tuple[str, ...] = ()) -> None:
        """Write ``to_text`` atomically (an existing file is replaced whole or not at all)."""
        atomic_write_text(Path(path), self.to_text(comments))


def parse_columns(text: str) -> dict[str, str]:
    """``x=x,z=y`` (scene axis = the file's column) -> {"x": "x", "z": "y"}; ValueError if malformed."""
    mapping: dict[str, str] = {}
    for part in text.split(","):
        axis, sep, column = (s.strip() for s in part.partition("="))
        if not sep or not column:
            raise ValueError(f"--columns {shown(text)}: expected AXIS=COLUMN pairs, e.g. x=x,z=y")
        if axis not in (*AXES, "t"):
            raise ValueError(f"--columns: {shown(axis)} is not t or a scene axis (x, y, z)")
        if axis in mapping:
            raise ValueError(f"--columns: {axis} is given twice")
        mapping[axis] = column
    return mapping


def _check_unit(unit, units, kind, name) -> None:
    if unit is not None and unit not in units:
        raise TrackError(f"{name}: unknown {kind} unit {shown(str(unit))} (known: {', '.join(units)})")


def _delimiter(line: str) -> str:
    """Tab, semicolon or comma: the one the line holds most of (a TSV's names hold no tabs)."""
    return max(("\t", ";", ","), key=line.count)


def _parsed_header(row: list[str]) -> list[tuple[str, str | None]] | None:
    """(name, unit or None) per cell, or None when a cell is not a column name."""
    names = []
    for cell in row:
        match = _HEADER.match(cell.strip().strip('"'))
        if match is None:
            return None
        names.append((match.group(1), match.group(2)))
    return names


def _find_header(rows, name, columns):
    time_name = (columns or {}).get("t", "t")
    for at in range(min(TITLE_LINES + 1, len(rows))):
        header = _parsed_header(rows[at])
        if header is not None and time_name in [n for n, _ in header]:
            return at, header
    raise TrackError(f"{name}: no header naming the columns {time_name!r} and x, y or z "
                     f"in its first {TITLE_LINES + 1} lines (e.g. t,x,y or t (s),x (cm),z (cm))")


def _wanted_columns(header, columns, name) -> dict[str, tuple[int, str | None]]:
    names = [n for n, _ in header]
    for n in names:
        if names.count(n) > 1:
            raise TrackError(f"{name}: the header names column {shown(n)} twice")
    mapping = dict(columns or {})
    mapping.setdefault("t", "t")
    if not any(axis in mapping for axis in AXES):
        mapping.update({axis: axis for axis in AXES if axis in names})
    wanted = {}
    for key, column in mapping.items():
        if column not in names:
            raise TrackError(f"{name}: no column {shown(column)} (for {key}); "
                             f"the header has {', '.join(map(shown, names))}")
        wanted[key] = (names.index(column), header[names.index(column)][1])
    measured = [axis for axis in AXES if axis in wanted]
    if len(measured) < 2:
        raise TrackError(f"{name}: a track needs two or three of x, y, z; "
                         f"found {', '.join(measured) or 'none'} (map columns to axes, e.g. x=x,z=y)")
    return wanted


def _number(cell: str, name: str, line: int, column: str) -> float:
    if cell in MISSING:
        return math.nan
    try:
        value = float(cell)
    except ValueError:
        raise TrackError(f"{name}: line {line}: column {shown(column)}: {shown(cell[:40])} is not a number") from None
    if not math.isfinite(value):
        raise TrackError(f"{name}: line {line}: column {shown(column)}: {shown(cell[:40])} is not a finite number")
    return value
