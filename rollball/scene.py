"""Scenes: everything needed to reproduce a run, as a validated, versioned JSON document.

The schema is declared once, as frozen dataclasses (key, type, default) plus a table of
constraints; the same validation serves files, the command line and the app. Every
refusal is a ``SceneError`` whose message starts with the offending key.
"""

from __future__ import annotations

import dataclasses
import decimal
import json
import math
import numbers
import os
import sys
import typing
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .files import atomic_write_text, open_regular
from .geometry import unit_normal
from .formula import FormulaError, check_parameter_names
from .landscape import landscape_for, landscape_of
from .tableaus import METHODS, get_method
from .text import shown

FORMAT = "rollball-scene"
VERSION = 4
MAX_FILE_SIZE = 1 << 20
MIN_RTOL = 10 * sys.float_info.epsilon   # tighter relative tolerances are below round-off
MAX_GRID_POINTS = 401   # per side of the drawn landscape (the app draws it; the core refuses more)
SMALLEST = sys.float_info.min   # the smallest normal positive float


class SceneError(ValueError):
    """A scene that cannot be accepted. ``key``: the offending dotted key ("scene" for the
    document as a whole); ``reason``: why. The message is "key: reason", the key escaped
    when it is not plain printable text (it may come from a hostile file)."""

    def __init__(self, key: str, reason: str | None = None):
        if reason is None:  # one "key: reason" text
            key, _, reason = key.partition(": ")
        self.key, self.reason = key, reason
        super().__init__(f"{shown(key)}: {reason}")


@dataclass(frozen=True)
class Ball:
    radius: float = 0.1
    mass: float = 1.0


@dataclass(frozen=True)
class Start:
    x: float = 0.3
    y: float = -0.2
    vx: float = 0.0
    vy: float = 0.0
    spin: float = 0.0
    # version 3: the initial angular velocity (world frame, rad/s) instead of the rolling one;
    # None: ω₀ = N × ċ₀ / r + spin · N
    omega: tuple[float, float, float] | None = None


AFTER_LIFTOFF = ("fly", "glued")   # what a ball does where the surface would have to pull it


@dataclass(frozen=True)
class Contact:
    """The contact model (version 3; docs/design.md §1). ``friction``: Coulomb's μ ≥ 0, or None
    for always enough friction to roll (the 2011 model); ``restitution``: e in [0, 1], the
    share of the normal speed a landing gives back; ``after_liftoff``: "fly" (the ball leaves
    the surface and lands again) or "glued" (it keeps rolling on the surface, the lift-off
    reported: the 2011 behaviour, what a version-2 file means)."""
    friction: float | None = None
    restitution: float = 0.0
    after_liftoff: str = "fly"
    # version 4 (docs/design.md §1, "Dissipation"): couples of size c_rr r F_n against the
    # rolling part of ω and μ_s r F_n against its spin about N
    rolling_resistance: float = 0.0
    spin_friction: float = 0.0


@dataclass(frozen=True)
class Air:
    """Air drag (version 4): a force −½ ρ C_d π r² |ċ| ċ on the centre, in flight too.
    ``density`` ρ (kg/m³, air 1.2) and ``drag_coefficient`` C_d (a smooth sphere ≈ 0.47): both
    0 (no air) or both given."""
    density: float = 0.0
    drag_coefficient: float = 0.0

    def drag_factor(self, radius: float) -> float:
        """k = ½ ρ C_d π r² (kg/m): the drag force is −k |ċ| ċ."""
        return 0.5 * self.density * self.drag_coefficient * math.pi * radius * radius


@dataclass(frozen=True)
class Integrator:
    method: str = "rk4"
    munthe_kaas: bool = True
    dt: float = 0.001
    rtol: float = 1e-6
    atol: float = 1e-9


@dataclass(frozen=True)
class Parameter:
    """A named number the formula uses (scene version 3). ``min``/``max``: the range a slider
    offers (both or neither); the value may lie outside it (a sweep may go beyond)."""
    name: str
    value: float
    min: float | None = None
    max: float | None = None


@dataclass(frozen=True)
class View:
    min: float = -3.0
    max: float = 3.0
    step: float = 0.1


def _positive(v):
    return None if v > 0 else "must be greater than 0"


def _normal_positive(v):
    return None if v >= SMALLEST else "must be a normal positive float (greater than 2.2e-308)"


def _not_negative(v):
    return None if v >= 0 else "must not be negative"


def _tolerance(v):
    if not v > 0:
        return "must be greater than 0"
    return None if v >= MIN_RTOL else f"must be at least {MIN_RTOL:.3g} (10 × the rounding error of a double)"


def _unit_interval(v):
    return None if 0.0 <= v <= 1.0 else "must be from 0 to 1"


def _after_liftoff(v):
    return None if v in AFTER_LIFTOFF else f"must be one of {', '.join(map(repr, AFTER_LIFTOFF))}"


def _known_method(v):
    try:
        get_method(v)
    except ValueError:
        return f"unknown method; valid methods: {', '.join(METHODS)}"
    return None


def _formula(v, parameters=()):
    try:
        landscape_for(v, parameters)  # parsed, differentiated and printed: ready to compile
    except FormulaError as e:
        return str(e)
    return None


# Constraints beyond the type, by dotted key.
CONSTRAINTS = {
    "landscape": _formula,
    "gravity": _not_negative,
    "ball.radius": _positive,
    "ball.mass": _positive,
    "integrator.method": _known_method,
    "integrator.dt": _positive,
    "integrator.rtol": _tolerance,
    "integrator.atol": _normal_positive,
    "duration": _positive,
    "view.step": _positive,
    "contact.friction": _not_negative,
    "contact.restitution": _unit_interval,
    "contact.after_liftoff": _after_liftoff,
    "contact.rolling_resistance": _not_negative,
    "contact.spin_friction": _not_negative,
    "air.density": _not_negative,
    "air.drag_coefficient": _not_negative,
}

# Keys whose value may be null (None), and keys holding a fixed number of numbers (a JSON array).
NULLABLE = ("contact.friction", "start.omega")
VECTORS = {"start.omega": 3}


@dataclass(frozen=True)
class Scene:
    landscape: str
    description: str = ""
    gravity: float = 9.81
    ball: Ball = field(default_factory=Ball)
    start: Start = field(default_factory=Start)
    integrator: Integrator = field(default_factory=Integrator)
    duration: float = 10.0
    view: View = field(default_factory=View)
    parameters: tuple[Parameter, ...] = ()   # version 3; also given as a dict as in a file
    contact: Contact = field(default_factory=Contact)   # version 3
    air: Air = field(default_factory=Air)   # version 4
    stop_at_rest: bool = True   # version 4: a run ends where the ball comes to rest

    @property
    def dissipates(self) -> bool:
        """Whether rolling resistance, spin friction or air take energy from a rolling ball
        (version 4); without them a rolling ball keeps its energy (the 2011 model)."""
        c = self.contact
        return c.rolling_resistance > 0.0 or c.spin_friction > 0.0 or self.air.density > 0.0

    def __post_init__(self):
        object.__setattr__(self, "parameters", _parameters(self.parameters))
        _check(self, "")
        if self.view.min >= self.view.max:
            raise SceneError("view.min", "must be less than view.max")
        method = get_method(self.integrator.method)
        if method.name != self.integrator.method:  # an alias: keep the method's own name
            object.__setattr__(self.integrator, "method", method.name)
        if not (method.classic_allowed or self.integrator.munthe_kaas):
            raise SceneError("integrator.munthe_kaas", f"{method.name} always uses Munthe-Kaas "
                             "(must be true)")
        _check_derived(self)

    # -- dictionaries and files -------------------------------------------------------

    @property
    def parameter_names(self) -> tuple[str, ...]:
        return tuple(p.name for p in self.parameters)

    @property
    def parameter_values(self) -> tuple[float, ...]:
        return tuple(p.value for p in self.parameters)

    def to_dict(self) -> dict:
        """The scene as a file holds it, always in the newest version (``VERSION``); keys at
        their defaults are written too, but ``parameters`` only when there are any and
        ``start.omega`` only when given (``contact`` always: its meaning differs by version)."""
        body = dataclasses.asdict(self)
        del body["parameters"]
        if self.start.omega is None:
            del body["start"]["omega"]
        else:
            body["start"]["omega"] = list(self.start.omega)
        if self.parameters:
            shown = {p.name: p.value if p.min is None else {"value": p.value, "min": p.min, "max": p.max}
                     for p in self.parameters}
            body = {"landscape": body.pop("landscape"), "parameters": shown, **body}
        return {"format": FORMAT, "version": VERSION, **body}

    @classmethod
    def from_dict(cls, data) -> "Scene":
        if not isinstance(data, dict):
            raise SceneError("scene", f"must be a JSON object, not {_kind(data)}")
        if "format" not in data:
            raise SceneError("format", f"missing (a RollBall scene has \"format\": \"{FORMAT}\")")
        if data["format"] != FORMAT:
            raise SceneError("format", f"must be \"{FORMAT}\"")
        if "version" not in data:
            raise SceneError("version", "missing")
        version = data["version"]
        if type(version) is not int or version < 1:
            raise SceneError("version", "must be a positive whole number")
        if version > VERSION:
            raise SceneError("version", f"{version} is newer than this RollBall understands "
                                        f"(it reads versions 1 to {VERSION})")
        if "landscape" not in data:
            raise SceneError("landscape", "missing")
        body = {k: v for k, v in data.items() if k not in ("format", "version")}
        for step in MIGRATIONS[version - 1:]:
            body = step(body)
        return _build(cls, body, "")

    @classmethod
    def loads(cls, text: str) -> "Scene":
        try:
            data = json.loads(text, parse_constant=_refuse_constant, object_pairs_hook=_no_duplicates)
        except SceneError:
            raise
        except RecursionError:
            raise SceneError("scene", "nested too deeply") from None
        except ValueError as e:
            if "int_max_str_digits" in str(e):  # Python's guard against quadratic int parsing
                raise SceneError("scene", f"a number has more than {sys.get_int_max_str_digits()} "
                                          "digits") from None
            raise SceneError("scene", f"not valid JSON ({e})") from None
        return cls.from_dict(data)

    @classmethod
    def load(cls, path: str | os.PathLike) -> "Scene":
        """Read a scene file; raises ``SceneError`` (or ``OSError`` if it cannot be read, or is
        not a regular file: a named pipe or a device is refused before it is opened)."""
        with open_regular(path) as stream:
            raw = stream.read(MAX_FILE_SIZE + 1)
        if len(raw) > MAX_FILE_SIZE:
            raise SceneError("scene", f"file is larger than {MAX_FILE_SIZE} bytes")
        try:
            text = raw.decode("utf-8-sig")
        except UnicodeDecodeError:
            raise SceneError("scene", "not a UTF-8 text file") from None
        return cls.loads(text)

    def dumps(self) -> str:
        return json.dumps(self.to_dict(), indent=2, ensure_ascii=False, allow_nan=False) + "\n"

    def save(self, path: str | os.PathLike) -> None:
        """Write the scene atomically: an existing file is replaced whole or not at all (and
        read-only or special files are refused; see ``rollball.files``)."""
        atomic_write_text(Path(path), self.dumps())


# -- migrations: one small function per version step, each taking the body (without
# "format" and "version") of one version to the next -------------------------------------

def _v1_to_v2(body: dict) -> dict:
    """Version 2 renamed the method ``adaptive`` to ``dopri5`` (and added dop853, gauss4)."""
    integrator = body.get("integrator")
    if isinstance(integrator, dict) and integrator.get("method") == "adaptive":
        body = {**body, "integrator": {**integrator, "method": "dopri5"}}
    return body


def _v2_to_v3(body: dict) -> dict:
    """Version 3 added ``parameters`` (named numbers in the formula), the contact model and
    ``start.omega``; a version-2 scene has none of them and runs as it did: a ball with
    always enough friction to roll that stays glued to the surface after a lift-off. Keys
    version 3 added are still unknown in a version-2 file."""
    for key in V3_KEYS:
        group, _, name = key.rpartition(".")
        holder = body.get(group) if group else body
        if isinstance(holder, dict) and name in holder:
            raise SceneError(key, "unknown key in a version-2 scene (it came with version 3)")
    return {**body, "contact": dict(V2_CONTACT)}


def _v3_to_v4(body: dict) -> dict:
    """Version 4 added rolling resistance, spin friction, air and ``stop_at_rest``; a
    version-3 scene has none of them and runs as it did. Keys version 4 added are still
    unknown in a version-3 file."""
    for key in V4_KEYS:
        group, _, name = key.rpartition(".")
        holder = body.get(group) if group else body
        if isinstance(holder, dict) and name in holder:
            raise SceneError(key, "unknown key in a version-3 scene (it came with version 4)")
    return body


# The (dotted) keys version 4 added.
V4_KEYS = ("contact.rolling_resistance", "contact.spin_friction", "air", "stop_at_rest")
# The (dotted) keys version 3 added.
V3_KEYS = ("parameters", "contact", "start.omega")
# What a version-2 scene's contact is: the 2011 model.
V2_CONTACT = {"friction": None, "restitution": 0.0, "after_liftoff": "glued"}

# MIGRATIONS[k] takes version k + 1 to version k + 2; a file of version v runs MIGRATIONS[v - 1:].
MIGRATIONS = [_v1_to_v2, _v2_to_v3, _v3_to_v4]
assert len(MIGRATIONS) == VERSION - 1


# Field types, resolved once: loading a scene evaluates nothing.
_HINTS = {cls: typing.get_type_hints(cls) for cls in (Scene, Ball, Start, Integrator, View, Contact, Air)}


def _number(key: str, value) -> float:
    """A finite number from a file or a caller (a bool is not one), as a plain float."""
    if isinstance(value, bool) or not isinstance(value, (numbers.Real, decimal.Decimal)):
        raise SceneError(key, f"must be a number, not {_kind(value)}")
    try:
        number = float(value)
    except OverflowError:
        raise SceneError(key, "number is too large") from None
    if not math.isfinite(number):
        raise SceneError(key, "must be a finite number")
    return number


def _parameters(given) -> tuple[Parameter, ...]:
    """``parameters`` as a file holds it (name -> number or {"value", "min", "max"}) or as
    ``Parameter``s, checked: names as formula.check_parameter_names, finite numbers, min < max
    with max − min finite."""
    objects = set()   # names given as {"value", ...}: their value's key is NAME.value
    if isinstance(given, dict):
        items = []
        for name, spec in given.items():
            key = f"parameters.{name}"
            if isinstance(spec, dict):
                unknown = [k for k in spec if k not in ("value", "min", "max")]
                if unknown:
                    raise SceneError(f"{key}.{unknown[0]}", "unknown key")
                if "value" not in spec:
                    raise SceneError(f"{key}.value", "missing")
                if ("min" in spec) != ("max" in spec):
                    raise SceneError(f"{key}.{'max' if 'min' in spec else 'min'}", "missing (a range has both ends)")
                items.append(Parameter(name, spec["value"], spec.get("min"), spec.get("max")))
                objects.add(name)
            else:
                items.append(Parameter(name, spec))
    elif isinstance(given, (tuple, list)) and all(isinstance(p, Parameter) for p in given):
        items = list(given)
    else:
        raise SceneError("parameters", f"must be an object (name: number), not {_kind(given)}")
    for p in items:
        if isinstance(p.name, str):
            _encodable(f"parameters.{p.name}", p.name)
    try:
        check_parameter_names([p.name for p in items])
    except FormulaError as e:
        bad = next((p.name for p in items if isinstance(p.name, str) and e.reason.startswith(repr(p.name))), None)
        raise SceneError(f"parameters.{bad}" if bad else "parameters", e.reason) from None
    checked = []
    for p in items:
        key = f"parameters.{p.name}"
        value = _number(f"{key}.value" if p.name in objects or p.min is not None else key, p.value)
        low = high = None
        if p.min is not None or p.max is not None:
            low, high = _number(f"{key}.min", p.min), _number(f"{key}.max", p.max)
            if not low < high:
                raise SceneError(f"{key}.min", f"must be less than max (got {low!r} and {high!r})")
            if not math.isfinite(high - low):   # a slider's steps are a thousandth of the width
                raise SceneError(f"{key}.max", f"the range is too wide: max − min overflows (got {low!r} "
                                               f"and {high!r})")
        checked.append(Parameter(p.name, value, low, high))
    return tuple(checked)


def _encodable(key: str, text: str) -> None:
    """Refuse text that UTF-8 cannot hold: a lone surrogate (JSON's "\\ud800" reads as one),
    which a scene could not be saved with."""
    try:
        text.encode("utf-8")
    except UnicodeEncodeError as e:
        raise SceneError(key, f"holds a lone surrogate ({text[e.start]!r} at character {e.start + 1}), "
                              "which no UTF-8 text can hold") from None


def _kind(value) -> str:
    kinds = {dict: "an object", list: "an array", str: "text", bool: "true/false", type(None): "null",
             int: "a number", float: "a number"}
    return kinds.get(type(value)) or f"a {type(value).__name__}"


def _refuse_constant(name):
    raise SceneError("scene", f"{name} is not a number JSON allows")


def _no_duplicates(pairs):
    data = {}
    for key, value in pairs:
        if key in data:
            raise SceneError(key, "appears twice")
        data[key] = value
    return data


def _build(cls, data: dict, prefix: str):
    hints = _HINTS[cls]
    names = {f.name for f in dataclasses.fields(cls)}
    for key in data:
        if key not in names:
            raise SceneError(f"{prefix}{key}", "unknown key")
    values = {}
    for key, value in data.items():
        kind = hints[key]
        if dataclasses.is_dataclass(kind):
            if not isinstance(value, dict):
                raise SceneError(f"{prefix}{key}", f"must be an object, not {_kind(value)}")
            value = _build(kind, value, f"{prefix}{key}.")
        values[key] = value
    try:
        return cls(**values)
    except TypeError:  # a required key is missing
        missing = [f.name for f in dataclasses.fields(cls) if f.name not in values]
        raise SceneError(f"{prefix}{missing[0]}", "missing") from None


def _check(obj, prefix: str) -> None:
    """Check types and constraints of a (nested) scene dataclass, in field order."""
    hints = _HINTS[type(obj)]
    for f in dataclasses.fields(obj):
        key, value, kind = prefix + f.name, getattr(obj, f.name), hints[f.name]
        if key == "parameters":   # checked by _parameters
            continue
        if value is None and key in NULLABLE:
            continue
        if key in VECTORS:
            object.__setattr__(obj, f.name, _vector(key, value, VECTORS[key]))
            continue
        if key in NULLABLE:   # a number where one is given
            kind = float
        if dataclasses.is_dataclass(kind):
            if not isinstance(value, kind):
                raise SceneError(key, "must be an object")
            _check(value, key + ".")
            continue
        if kind is float:
            number = _number(key, value)
            if type(value) is not float:  # int, numpy numbers: stored as a plain float
                object.__setattr__(obj, f.name, number)
            value = number
        elif kind is bool and type(value) is not bool:
            raise SceneError(key, f"must be true or false, not {_kind(value)}")
        elif kind is str and type(value) is not str:
            raise SceneError(key, f"must be text, not {_kind(value)}")
        if kind is str:
            _encodable(key, value)
        if key == "landscape":   # with the names of the scene's parameters
            problem = _formula(value, tuple(p.name for p in getattr(obj, "parameters", ())))
        else:
            problem = CONSTRAINTS.get(key, lambda v: None)(value)
        if problem:
            raise SceneError(key, f"{problem} (got {value!r})" if kind is float else problem)


def _vector(key: str, value, size: int) -> tuple[float, ...]:
    """A JSON array (or a tuple) of ``size`` finite numbers, as a tuple of plain floats."""
    if not isinstance(value, (list, tuple)):
        raise SceneError(key, f"must be an array of {size} numbers, not {_kind(value)}")
    if len(value) != size:
        raise SceneError(key, f"must be an array of {size} numbers, not of {len(value)}")
    return tuple(_number(f"{key}[{i}]", item) for i, item in enumerate(value))


def _finite(*factors: float) -> bool:
    product = 1.0
    for factor in factors:
        product *= factor
    return math.isfinite(product)


def _check_derived(scene: Scene) -> None:
    """What the physics and the drawing need beyond each value on its own: the quantities the
    equations divide by or add up must be normal floats (no underflow to 0, no overflow)."""
    r, m, g, s = scene.ball.radius, scene.ball.mass, scene.gravity, scene.start
    if not SMALLEST <= r * r < math.inf:
        raise SceneError("ball.radius", f"r² must be a normal positive float (got r = {r!r})")
    inertia = m * r * r
    if not SMALLEST <= inertia < math.inf:
        raise SceneError("ball.mass", f"m r² must be a normal positive float (got m = {m!r}, r = {r!r})")
    if not _finite(m, g, r):
        raise SceneError("gravity", f"m g₀ r overflows (got g₀ = {g!r})")
    speed2 = s.vx * s.vx + s.vy * s.vy
    if not _finite(m, speed2, 2.0):
        raise SceneError("start.vx" if abs(s.vx) >= abs(s.vy) else "start.vy",
                         "the kinetic energy m v² overflows")
    if not _finite(inertia, s.spin, s.spin, 2.0):
        raise SceneError("start.spin", "the kinetic energy m r² spin² overflows")
    if s.omega is not None:
        if s.spin != 0.0:
            raise SceneError("start.spin", "must be 0 when start.omega is given (ω's part along the normal "
                                           "is the spin)")
        if not _finite(inertia, sum(w * w for w in s.omega), 2.0):
            raise SceneError("start.omega", "the kinetic energy m r² |ω|² overflows")
        _check_rolls(scene)
    air = scene.air
    if (air.density > 0.0) != (air.drag_coefficient > 0.0):
        given, other = ("air.density", "air.drag_coefficient") if air.density > 0.0 else \
            ("air.drag_coefficient", "air.density")
        raise SceneError(other, f"must be given with {given} (air drags with both, or neither is given)")
    if not _finite(air.density, air.drag_coefficient, r, r, math.pi):
        raise SceneError("air.density", "the drag factor ½ ρ C_d π r² overflows")
    v = scene.view
    points = (v.max - v.min) / v.step + 1
    if not points <= MAX_GRID_POINTS:  # also catches an overflowing (infinite) span
        shown_points = f"{math.ceil(points):,}" if math.isfinite(points) else "too many"
        raise SceneError("view.step", f"{shown_points} grid points per side; at most {MAX_GRID_POINTS}")


# A start.omega rolls when the contact point's slip speed is below this share of the speeds
# involved (|ċ₀| and r|ω₀|): room for the digits a file gives, far below any real slip.
ROLLING_TOLERANCE = 1e-9


def start_slip(scene: Scene) -> np.ndarray | None:
    """The velocity of the ball's material point at the contact at the start,
    u = ċ₀ + ω₀ × (−r N), for a scene with ``start.omega`` (None without one, or where the
    landscape cannot be evaluated at the start: the run reports that)."""
    s, r = scene.start, scene.ball.radius
    if s.omega is None:
        return None
    with np.errstate(all="ignore"):
        d = landscape_of(scene).evaluate(s.x, s.y, scene.parameter_values)
        if not np.all(np.isfinite(d[:3])):
            return None
        normal = unit_normal(d)
        velocity = np.array([s.vx, s.vy, d[1] * s.vx + d[2] * s.vy])
        return velocity - r * np.cross(np.array(s.omega), normal)


def _check_rolls(scene: Scene) -> None:
    """With friction null the ball can only roll: a start.omega whose contact point slips is refused."""
    if scene.contact.friction is not None:
        return   # it slips until friction makes it roll
    slip = start_slip(scene)
    if slip is None:
        return
    s, r = scene.start, scene.ball.radius
    speed = float(np.linalg.norm(slip))
    scale = max(math.hypot(s.vx, s.vy), r * math.sqrt(sum(w * w for w in s.omega)))
    if speed > ROLLING_TOLERANCE * scale:
        raise SceneError("start.omega", f"the ball does not roll at the start (its contact point slips at "
                                        f"{speed:.3g} m/s); with contact.friction null it can only roll: give "
                                        f"ω = N × ċ / r + spin · N, or a friction coefficient")
