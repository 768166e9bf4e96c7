"""Hostile and broken input, declared as data: each entry is (input, the expected message fragment).

Formulas must be refused with a ``FormulaError`` containing the fragment, quickly, without
any text being evaluated; ``DERIVATIONS`` parse but would cost unbounded work to differentiate
and must be refused by the work budget within a few seconds. Scene texts must be refused with a
``SceneError`` whose ``key`` is the key given (the message starts with it, escaped when it is
not printable). ``RUNS`` are command lines that must end with exit 2 and one line.
"""

# -- formulas: group -> [(text, fragment of the FormulaError message)] --------------------------------

FORMULAS = {
    "injection": [
        ('__import__("os").system("touch /tmp/rollball-pwned")', "unexpected character '\"' at 12"),
        ("__import__('os')", "unexpected character \"'\" at 12"),
        ("__import__", "unknown name '__import__' at 1"),
        ("().__class__.__bases__[0].__subclasses__()", "unexpected character '[' at 23"),
        ("x.__class__", "unexpected character '.' at 2"),
        ("x.real", "unexpected character '.' at 2"),
        ("sin.__globals__", "unexpected character '.' at 4"),
        ("exp.__call__(x)", "unexpected character '.' at 4"),
        ("lambda: 0", "unexpected character ':' at 7"),
        ("(lambda x: x)(1)", "unexpected character ':' at 10"),
        ("[x for x in (1, 2)]", "unexpected character '[' at 1"),
        ("(x for x in y)", "expected ')' but found 'for' at 4"),
        ("{x: 1}", "unexpected character '{' at 1"),
        ("'text'", "unexpected character \"'\" at 1"),
        ('"text"', "unexpected character '\"' at 1"),
        ("b'x'", "unexpected character \"'\" at 2"),
        ("(y := 2)", "unexpected character ':' at 4"),
        ("x if y else 1", "missing operator before 'if' at 3"),
        ("eval(x)", "unknown name 'eval' at 1"),
        ("exec(x)", "unknown name 'exec' at 1"),
        ("open(x)", "unknown name 'open' at 1"),
        ("getattr(x, y)", "unknown name 'getattr' at 1"),
        ("globals()", "unknown name 'globals' at 1"),
        ("print(1)", "unknown name 'print' at 1"),
        ("sympify(x)", "unknown name 'sympify' at 1"),
        ("Symbol(x)", "unknown name 'Symbol' at 1"),
        ("__builtins__", "unknown name '__builtins__' at 1"),
        ("_", "unknown name '_' at 1"),
        ("x[0]", "unexpected character '[' at 2"),
        ("x; import os", "unexpected character ';' at 2"),
        ("import os", "unknown name 'import' at 1"),
        ("x\nimport os", "unexpected character 'U+000A' at 2"),
        ("x # comment", "unexpected character '#' at 3"),
        ("`x`", "unexpected character '`' at 1"),
        ("x @ y", "unexpected character '@' at 3"),
        ("x & y", "unexpected character '&' at 3"),
        ("x == y", "unexpected character '=' at 3"),
        ("x % 2", "unexpected character '%' at 3"),
        ("x\\\ny", "unexpected character '\\\\' at 2"),
    ],
    "malformed": [
        ("(x + 1", "unbalanced parenthesis at 1"),
        ("x + 1)", "unbalanced parenthesis at 6"),
        ("sin(x", "unbalanced parenthesis at 4"),
        ("x +", "formula ends too early at 4"),
        ("x^", "formula ends too early at 3"),
        ("^x", "unexpected '^' at 1"),
        ("x * * y", "unexpected '*' at 5"),
        ("2 x", "missing operator before 'x' at 3"),
        ("x, y", "missing operator before ',' at 2"),
        ("sin(x)(y)", "missing operator before '(' at 7"),
        ("sin x", "function 'sin' needs its arguments in parentheses at 1"),
        ("sin()", "unexpected ')' at 5"),
        ("x(2)", "'x' is not a function at 1"),
        ("atan2(x)", "atan2 takes 2 arguments, not 1 at 1"),
        ("sin(x, y)", "sin takes 1 argument, not 2 at 1"),
        ("max(x)", "max takes two or more arguments at 1"),
        ("1/0", "division by zero at 2"),
        ("x / (y - y)", "division by zero at 3"),
        ("1..2", "missing operator before '.2' at 3"),
        ("0x10", "missing operator before 'x10' at 2"),
        ("1_000", "missing operator before '_000' at 2"),
        ("log(-1)", "not real"),
        ("acos(2)", "not real"),
        ("", "formula is empty"),
        ("   ", "formula is empty"),
        ("x;y", "unexpected character ';' at 2"),
        ("x\ry", "unexpected character 'U+000D' at 2"),
    ],
    "unknown names": [
        ("t", "unknown name 't' at 1"),
        ("x + t", "unknown name 't' at 5"),
        ("z", "unknown name 'z' at 1"),
        ("x + sinx", "unknown name 'sinx' at 5"),
        ("X", "unknown name 'X' at 1"),
        ("Sin(x)", "unknown name 'Sin' at 1"),
        ("PI", "unknown name 'PI' at 1"),
        ("E", "unknown name 'E' at 1"),
        ("inf", "unknown name 'inf' at 1"),
        ("nan", "unknown name 'nan' at 1"),
        ("I", "unknown name 'I' at 1"),
        ("oo", "unknown name 'oo' at 1"),
        ("zoo", "unknown name 'zoo' at 1"),
        ("factorial(1000000)", "unknown name 'factorial' at 1"),
        ("gamma(x)", "unknown name 'gamma' at 1"),
    ],
    "unicode look-alikes": [
        ("х + 1", "unexpected character 'х' at 1"),            # Cyrillic x
        ("x + ｙ", "unexpected character 'ｙ' at 5"),           # full-width y
        ("１ + x", "unexpected character '１' at 1"),           # full-width 1
        ("ｓｉｎ(x)", "unexpected character 'ｓ' at 1"),          # full-width sin
        ("ⅹ", "unexpected character 'ⅹ' at 1"),                # Roman numeral ten
        ("x\u2212y", "unexpected character '\u2212' at 2"),     # minus sign
        ("sin(x)\u200b", "unexpected character 'U+200B' at 7"),  # zero-width space
        ("x\u00a0+ 1", "unexpected character 'U+00A0' at 2"),    # non-breaking space
        ("x\ufeff", "unexpected character 'U+FEFF' at 2"),       # byte order mark
        ("x\x00", "unexpected character 'U+0000' at 2"),
    ],
    "size and hangs": [
        ("x" * 1001, "formula is too long (1001 characters, at most 1000)"),
        ("x" + "+x" * 600, "formula is too long"),
        ("(" * 45 + "x" + ")" * 45, "nested too deeply"),
        ("sin(" * 45 + "x" + ")" * 45, "nested too deeply"),
        ("-" * 500 + "x", "nested too deeply"),
        ("1e999 * x", "number 1e999 is too large at 1"),
        ("10^400", "constant power is too large at 3"),
        ("9**9**9**9", "constant power is too large at 5"),
        ("9^9^9^9^9^9", "constant power is too large at 8"),
        ("2^2^2^2^2^2^2", "constant power is too large at 6"),
        ("(1+1e-15)^(10^300)", "constant power is too large at 10"),
        ("x^(10^400)", "constant power is too large at 6"),
        ("exp(1e300)", "constant value of exp is too large at 1"),
        ("exp(exp(exp(100)))", "constant value of exp is too large at 5"),
        ("sinh(sinh(sinh(100)))", "constant value of sinh is too large at 6"),
        ("cosh(cosh(cosh(cosh(9))))", "constant value of cosh is too large at 11"),
        ("x + exp(exp(300)*exp(300)*exp(300)*exp(300))", "too large"),
        ("tan(pi/2)", "constant value of tan is too large at 1"),
        ("max(" + ",".join(f"sin({k}*x)" for k in range(1, 90)) + ")", "max takes at most 16 arguments at 1"),
        ("min(" + ",".join(f"x*{k}+y" for k in range(1, 18)) + ")", "min takes at most 16 arguments at 1"),
    ],
}

# -- formulas that parse but explode when differentiated: (text, fragment) ------------------------------

_TOO_COMPLEX = "formula too complex to differentiate"
DERIVATIONS = [
    ("*".join(f"sin({k}*x+y)" for k in range(1, 84)), _TOO_COMPLEX),        # 986 characters
    ("*".join(f"sin({k}*x+y)" for k in range(1, 19)), _TOO_COMPLEX),        # 212 characters
    ("*".join(f"(x+{k}*y)" for k in range(1, 91)), _TOO_COMPLEX),
    ("*".join(f"exp({k}*x*y)*cos(x-{k}*y)" for k in range(1, 30)), _TOO_COMPLEX),
    ("^".join(["x"] * 39), _TOO_COMPLEX),                                  # power tower
    ("exp(sin(" * 19 + "x*y" + "))" * 19, _TOO_COMPLEX),
    ("(" * 38 + "x+y" + "".join(f")^2+{'x' if i % 2 else 'y'}" for i in range(38)), _TOO_COMPLEX),
    ("min(" + ",".join(f"sin({k}*x)" for k in range(1, 17)) + ")", _TOO_COMPLEX),
    ("atan2(" * 30 + "x" + ", x*y)" * 30, _TOO_COMPLEX),
]

# -- scene files: group -> [(text, the key the SceneError message starts with)] ------------------------

_HEAD = '"format": "rollball-scene", "version": 2'


def _scene(body: str) -> str:
    return "{" + _HEAD + ", " + body + "}"


SCENE_TEXTS = {
    "not a scene": [
        ("", "scene"),
        ("   \n", "scene"),
        ("not json", "scene"),
        ("[]", "scene"),
        ('["rollball-scene"]', "scene"),
        ("null", "scene"),
        ("42", "scene"),
        ('"text"', "scene"),
        (_scene('"landscape": "x"')[:-1], "scene"),  # truncated
        (_scene('"landscape": "x", "ball": {"radius": 0.1')[:-1], "scene"),
        ("[" * 100000, "scene"),
        ('{"a":' * 100000, "scene"),
    ],
    "numbers": [
        (_scene('"landscape": "x", "gravity": NaN'), "scene"),
        (_scene('"landscape": "x", "gravity": Infinity'), "scene"),
        (_scene('"landscape": "x", "gravity": -Infinity'), "scene"),
        (_scene('"landscape": "x", "gravity": 1e999'), "gravity"),
        (_scene('"landscape": "x", "start": {"x": -1e999}'), "start.x"),
        (_scene('"landscape": "x", "start": {"x": ' + "9" * 400 + "}"), "start.x"),
        (_scene('"landscape": "x", "start": {"x": ' + "9" * 5000 + "}"), "scene"),
        (_scene('"landscape": "x", "gravity": 0.' + "0" * 5000 + "1}"), "scene"),
        (_scene('"landscape": "x", "duration": -' + "1" * 4400 + "}"), "scene"),
    ],
    "derived quantities": [
        (_scene('"landscape": "x", "ball": {"radius": 1e-170}'), "ball.radius"),      # r² underflows
        (_scene('"landscape": "x", "ball": {"radius": 1e-160}'), "ball.radius"),      # r² subnormal
        (_scene('"landscape": "x", "ball": {"radius": 1e300}'), "ball.radius"),       # r² overflows
        (_scene('"landscape": "x", "ball": {"mass": 5e-324}'), "ball.mass"),          # m r² underflows
        (_scene('"landscape": "x", "ball": {"mass": 1e-300, "radius": 1e-5}'), "ball.mass"),
        (_scene('"landscape": "x", "ball": {"mass": 1e300, "radius": 1e10}'), "ball.mass"),
        (_scene('"landscape": "x", "gravity": 1e308, "ball": {"radius": 100}'), "gravity"),
        (_scene('"landscape": "x", "start": {"vx": 1e200}'), "start.vx"),
        (_scene('"landscape": "x", "start": {"vy": -3e160}'), "start.vy"),
        (_scene('"landscape": "x", "start": {"spin": 1e300}'), "start.spin"),
        (_scene('"landscape": "x", "integrator": {"rtol": 1e-300}'), "integrator.rtol"),
        (_scene('"landscape": "x", "integrator": {"rtol": 1e-16}'), "integrator.rtol"),
        (_scene('"landscape": "x", "integrator": {"atol": 5e-324}'), "integrator.atol"),
    ],
    "grids": [
        (_scene('"landscape": "x", "view": {"step": 0.0005}'), "view.step"),
        (_scene('"landscape": "x", "view": {"min": -1, "max": 1, "step": 0.004}'), "view.step"),
        (_scene('"landscape": "x", "view": {"min": -1e300, "max": 1e300}'), "view.step"),
        (_scene('"landscape": "x", "view": {"min": -1.7e308, "max": 1.7e308, "step": 1e308}'), "view.step"),
        (_scene('"landscape": "x", "view": {"min": 0, "max": 1e-300, "step": 5e-324}'), "view.step"),
    ],
    "keys that would act on a terminal": [
        (_scene('"landscape": "x", "a\\nrollball: fake line": 1'), "a\nrollball: fake line"),
        (_scene('"landscape": "x", "\\u001b[2J": 1'), "\x1b[2J"),
        (_scene('"landscape": "x", "\\u001b]0;pwned\\u0007": 1'), "\x1b]0;pwned\x07"),
        (_scene('"landscape": "x", "ball": {"\\u009b31m": 1}'), "ball.\x9b31m"),
        (_scene('"landscape": "x", "x\\u202egnp.exe": 1'), "x\u202egnp.exe"),
        (_scene('"landscape": "x", "x\\u202egnp.exe": 1, "x\\u202egnp.exe": 2'), "x\u202egnp.exe"),
    ],
    "wrong types": [
        (_scene('"landscape": 5'), "landscape"),
        (_scene('"landscape": ["x"]'), "landscape"),
        (_scene('"landscape": "x", "ball": {"radius": "0.1"}'), "ball.radius"),
        (_scene('"landscape": "x", "ball": {"radius": true}'), "ball.radius"),
        (_scene('"landscape": "x", "ball": {"radius": null}'), "ball.radius"),
        (_scene('"landscape": "x", "ball": [0.1, 1.0]'), "ball"),
        (_scene('"landscape": "x", "ball": 0.1'), "ball"),
        (_scene('"landscape": "x", "integrator": {"munthe_kaas": 1}'), "integrator.munthe_kaas"),
        (_scene('"landscape": "x", "integrator": {"method": 4}'), "integrator.method"),
        (_scene('"landscape": "x", "description": ["a"]'), "description"),
        ('{"format": "rollball-scene", "version": "1", "landscape": "x"}', "version"),
        ('{"format": "rollball-scene", "version": 1.0, "landscape": "x"}', "version"),
        ('{"format": "rollball-scene", "version": true, "landscape": "x"}', "version"),
        ('{"format": 1, "version": 1, "landscape": "x"}', "format"),
    ],
    "missing, unknown and duplicate keys": [
        ('{"version": 1, "landscape": "x"}', "format"),
        ('{"format": "rollball-scene", "landscape": "x"}', "version"),
        ("{" + _HEAD + "}", "landscape"),
        (_scene('"landscape": "x", "colour": "red"'), "colour"),
        (_scene('"landscape": "x", "ball": {"colour": "red"}'), "ball.colour"),
        (_scene('"landscape": "x", "__class__": {}'), "__class__"),
        (_scene('"landscape": "x", "landscape": "y"'), "landscape"),
        (_scene('"landscape": "x", "ball": {"radius": 0.1, "radius": 0.2}'), "radius"),
    ],
    "values out of range": [
        (_scene('"landscape": "x", "ball": {"radius": 0}'), "ball.radius"),
        (_scene('"landscape": "x", "ball": {"radius": -0.1}'), "ball.radius"),
        (_scene('"landscape": "x", "ball": {"mass": 0}'), "ball.mass"),
        (_scene('"landscape": "x", "ball": {"mass": -1}'), "ball.mass"),
        (_scene('"landscape": "x", "integrator": {"dt": 0}'), "integrator.dt"),
        (_scene('"landscape": "x", "integrator": {"dt": -0.001}'), "integrator.dt"),
        (_scene('"landscape": "x", "duration": 0'), "duration"),
        (_scene('"landscape": "x", "duration": -1'), "duration"),
        (_scene('"landscape": "x", "gravity": -9.81'), "gravity"),
        (_scene('"landscape": "x", "view": {"min": 3.0}'), "view.min"),
        (_scene('"landscape": "x", "view": {"min": 1.0, "max": 1.0}'), "view.min"),
        (_scene('"landscape": "x", "view": {"step": 0}'), "view.step"),
        (_scene('"landscape": "x", "integrator": {"method": "rk45"}'), "integrator.method"),
        (_scene('"landscape": "x", "integrator": {"method": "RK4"}'), "integrator.method"),
        ('{"format": "rollball-scene", "version": 5, "landscape": "x"}', "version"),
        ('{"format": "rollball-scene", "version": 0, "landscape": "x"}', "version"),
        ('{"format": "something-else", "version": 1, "landscape": "x"}', "format"),
    ],
    "hostile landscapes": [
        (_scene('"landscape": "__import__(\\"os\\").system(\\"ls\\")"'), "landscape"),
        (_scene('"landscape": "z + 1"'), "landscape"),
        (_scene('"landscape": "9**9**9**9"'), "landscape"),
        (_scene('"landscape": "exp(exp(exp(100)))"'), "landscape"),
        (_scene('"landscape": "' + "x" * 5000 + '"'), "landscape"),
    ],
}

# -- scene files as bytes: (bytes, fragment of the SceneError message) --------------------------------

SCENE_BYTES = [
    (b"\x89PNG\r\n\x1a\n\x00\xff\xfe", "not a UTF-8 text file"),
    (b"\xff\xfe{\x00}\x00", "not a UTF-8 text file"),  # UTF-16
    (_scene('"landscape": "x", "description": "caf\xe9"').encode("latin-1"), "not a UTF-8 text file"),
    (b" " * (2 << 20), "file is larger than"),
    (b"\x00" * 100, "not valid JSON"),
]
