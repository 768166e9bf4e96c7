"""What a sweep varies: scene keys, their values, and the full grid of runs over them."""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from ..formula import parameter_problem
from ..scene import Parameter, Scene
from .options import KEYS, SWITCHES

MAX_RUNS = 10_000_000  # a larger grid is refused (its outcomes alone would fill gigabytes)


def parse_vary(text: str) -> tuple[str, np.ndarray]:
    """``KEY=START:STOP:N`` -> (key, N evenly spaced values from START to STOP, both included)."""
    key, sep, spec = text.partition("=")
    key = key.strip()
    if not sep:
        raise ValueError(f"--vary {text!r}: expected KEY=START:STOP:N")
    _known(key)
    parts = spec.split(":")
    if len(parts) != 3:
        raise ValueError(f"--vary {text!r}: expected KEY=START:STOP:N, e.g. start.vx=3:6:61")
    try:
        lo, hi = float(parts[0]), float(parts[1])
    except ValueError:
        raise ValueError(f"--vary {key}: START and STOP must be numbers, not {parts[0]!r}, {parts[1]!r}") from None
    try:
        n = int(parts[2])
    except ValueError:
        raise ValueError(f"--vary {key}: N must be a whole number, not {parts[2]!r}") from None
    if not (math.isfinite(lo) and math.isfinite(hi)):
        raise ValueError(f"--vary {key}: START and STOP must be finite numbers")
    if n < 1:
        raise ValueError(f"--vary {key}: N must be 1 or more, not {n}")
    if n > MAX_RUNS:
        raise ValueError(f"--vary {key}: N = {n:,} values is more than a sweep may run ({MAX_RUNS:,})")
    return key, (np.array([lo]) if n == 1 else np.linspace(lo, hi, n))


PARAMETER_PREFIX = "parameters."   # parameters.NAME: a parameter of the scene's formula (version 3)


def _known(key) -> None:
    if key.startswith(PARAMETER_PREFIX):
        if parameter_problem(key[len(PARAMETER_PREFIX):]) is None:
            return
    if key not in KEYS:
        raise ValueError(f"cannot vary {key!r}; the keys a sweep varies: {', '.join(KEYS)}, "
                         f"and parameters.NAME for a parameter of the scene")


def unit(key: str) -> str:
    """The unit of a varied key (a parameter's is the formula's business: none)."""
    return KEYS.get(key, "")


def check_keys(scene: Scene, keys) -> None:
    """Refuse (ValueError) varying a parameter the scene does not declare."""
    for key in keys:
        if key.startswith(PARAMETER_PREFIX) and key[len(PARAMETER_PREFIX):] not in scene.parameter_names:
            declared = ", ".join(scene.parameter_names) or "none"
            raise ValueError(f"cannot vary {key!r}: the scene has no parameter "
                             f"{key[len(PARAMETER_PREFIX):]!r} (its parameters: {declared})")


@dataclasses.dataclass(frozen=True)
class Grid:
    """The runs of a sweep: every combination of the varied values, in row-major order of
    the keys (the last key varies fastest)."""

    keys: tuple[str, ...]
    axes: tuple[np.ndarray, ...]

    @classmethod
    def of(cls, vary) -> "Grid":
        """From a mapping key -> values (or (key, values) pairs); refuses unknown keys, values
        that are not finite numbers, empty axes, keys given twice and grids over MAX_RUNS."""
        items = list(vary.items()) if isinstance(vary, dict) else list(vary)
        if not items:
            raise ValueError("a sweep needs at least one key to vary")
        keys, axes = [], []
        for key, values in items:
            _known(key)
            if key in keys:
                raise ValueError(f"{key} is varied twice")
            try:
                array = np.array(values, dtype=float, ndmin=1)
            except (TypeError, ValueError):
                raise ValueError(f"{key}: the values must be numbers") from None
            if array.ndim != 1 or array.size == 0:
                raise ValueError(f"{key}: needs a flat, non-empty list of values")
            if not np.all(np.isfinite(array)):
                raise ValueError(f"{key}: the values must be finite numbers")
            if key in SWITCHES:
                if not np.all((array == 0.0) | (array == 1.0)):
                    raise ValueError(f"{key}: the values must be 0 (false) or 1 (true)")
            elif any(isinstance(v, bool) for v in np.asarray(values, dtype=object).ravel()):
                raise ValueError(f"{key}: the values must be numbers, not true/false")
            keys.append(key)
            axes.append(array)
        size = math.prod(len(a) for a in axes)
        if size > MAX_RUNS:
            raise ValueError(f"the grid has {size:,} runs, more than a sweep may run ({MAX_RUNS:,})")
        for a in axes:
            a.setflags(write=False)
        return cls(tuple(keys), tuple(axes))

    @property
    def shape(self) -> tuple[int, ...]:
        return tuple(len(a) for a in self.axes)

    @property
    def size(self) -> int:
        return math.prod(self.shape)

    def values(self, lo: int = 0, hi: int | None = None) -> np.ndarray:
        """The varied values of runs lo .. hi-1: shape (runs, keys)."""
        hi = self.size if hi is None else hi
        index = np.unravel_index(np.arange(lo, hi), self.shape)
        return np.stack([a[i] for a, i in zip(self.axes, index)], axis=1)


def value_of(scene: Scene, key: str) -> float:
    """The scene's value of a dotted key (a null friction is inf: always enough to roll)."""
    if key.startswith(PARAMETER_PREFIX):
        check_keys(scene, [key])
        return scene.parameter_values[scene.parameter_names.index(key[len(PARAMETER_PREFIX):])]
    obj = scene
    for part in key.split("."):
        obj = getattr(obj, part)
    return math.inf if obj is None else float(obj)   # (friction null: always enough friction)


def with_value(scene: Scene, key: str, value: float) -> Scene:
    """The scene with one dotted key set (validated like a scene file: ``SceneError``)."""
    if key.startswith(PARAMETER_PREFIX):
        check_keys(scene, [key])
        name = key[len(PARAMETER_PREFIX):]
        return dataclasses.replace(scene, parameters=tuple(
            Parameter(p.name, value, p.min, p.max) if p.name == name else p for p in scene.parameters))
    group, _, name = key.rpartition(".")
    value = _scene_value(key, value)
    if not group:
        return dataclasses.replace(scene, **{name: value})
    return dataclasses.replace(scene, **{group: dataclasses.replace(getattr(scene, group), **{name: value})})


def _scene_value(key: str, value):
    """A swept number as the scene holds it: a switch's 0 or 1 as false or true (others refused
    as the scene refuses a number there)."""
    if key in SWITCHES and value in (0, 1):
        return bool(value)
    return value


def with_values(scene: Scene, keys, values) -> Scene:
    """The scene with the dotted keys set (validated like a scene file: ``SceneError``). Each part
    (``start``, ``ball``, ...) is made once with all its new values, then the scene once: what
    a run of a sweep pays for its scene (a check of the whole scene each)."""
    parts: dict[str, dict] = {}
    for key, value in zip(keys, values):
        if key.startswith(PARAMETER_PREFIX):
            scene = with_value(scene, key, float(value))
            continue
        group, _, name = key.rpartition(".")
        parts.setdefault(group, {})[name] = _scene_value(key, value)
    if not parts:
        return scene
    changes = parts.pop("", {})
    changes.update({group: dataclasses.replace(getattr(scene, group), **names) for group, names in parts.items()})
    return dataclasses.replace(scene, **changes)
