"""The kernel's machine code: made from the shipped LLVM code where it fits, else by numba;
its arguments packed by name and kind, as the kernel's interface declares them; the shipped
code checked against what it was made from before anything of it is called."""

import hashlib
import json
import shutil
from importlib import resources

import numpy as np
import pytest

from rollball import kernel, machine_code
from rollball.kernel import entries, interface, unpacking
from rollball.landscape import landscape_for


_RECORDS = []   # the landscapes' records, held while the kernel may run them


def _points(xs, ys):
    _RECORDS.append(landscape_for("x^2 + 3*y").record())
    return machine_code.Arguments("evaluate_points", fn=_RECORDS[-1].ctypes.data, xs=xs, ys=ys,
                                  out=np.empty((6, len(xs))), d=np.empty(6))


_EMITTED: dict[str, bytes] = {}   # object code by the SHA-256 of the bitcode LLVM made it from


@pytest.fixture
def emit_once(monkeypatch):
    """LLVM's code generation of the shipped kernel (about 5 s of CPU time) done once for the
    tests that make its machine code again and again: every step around it (reading, checking,
    keeping, refusing, warning, loading) runs each time as before; only the same bitcode is not
    handed to the code generator twice."""
    real = machine_code.target_machine

    class Machine:
        def __init__(self):
            self.machine = real()

        def __getattr__(self, name):
            return getattr(self.machine, name)

        def emit_object(self, module):
            key = hashlib.sha256(module.as_bitcode()).hexdigest()
            if key not in _EMITTED:
                _EMITTED[key] = self.machine.emit_object(module)
            return _EMITTED[key]

    monkeypatch.setattr(machine_code, "target_machine", Machine)


def _shipped_or_skip(folder=None):
    try:
        return machine_code._shipped(folder)
    except machine_code._Unusable as error:
        pytest.skip(f"the shipped code does not fit here ({error}): numba's way is used instead (every run "
                    f"compiles the kernel with numba once)")


def test_arguments_run_the_kernel_and_one_can_be_changed_by_name():
    call = _points(np.array([1.0, 2.0]), np.array([0.5, -1.0]))
    call()
    assert call.kept["out"][0].tolist() == [2.5, 1.0]   # f = x^2 + 3y
    call.set("xs", np.array([3.0, 0.0]))
    call()
    assert call.kept["out"][0].tolist() == [10.5, -3.0] and call.kept["out"][1].tolist() == [6.0, 0.0]   # f, f_x


@pytest.mark.parametrize("xs, words", [(np.array([1, 2]), "xs must be a C-contiguous vector of float64"),
                                       (np.zeros((2, 2)), "xs must be a C-contiguous vector of float64"),
                                       (np.zeros(4)[::2], "xs must be a C-contiguous vector of float64")])
def test_an_array_of_the_wrong_kind_is_refused_by_name(xs, words):
    with pytest.raises(TypeError, match=words):
        _points(xs, np.zeros(2))


def test_arguments_are_given_by_their_declared_names_only():
    # Two arguments of one kind swapped at a call site would run and give wrong numbers: so no
    # argument goes by position, and every name must be one the interface declares
    arrays = dict(xs=np.zeros(1), ys=np.zeros(1), out=np.zeros((6, 1)), d=np.zeros(6))
    with pytest.raises(TypeError):
        machine_code.Arguments("evaluate_points", 0, np.zeros(1), np.zeros(1), np.zeros((6, 1)), np.zeros(6))
    with pytest.raises(TypeError, match="missing fn"):
        machine_code.Arguments("evaluate_points", **arrays)
    with pytest.raises(TypeError, match="unknown x"):
        machine_code.Arguments("evaluate_points", fn=0, x=np.zeros(1), **arrays)
    with pytest.raises(TypeError, match="no argument t_end"):
        _points(np.zeros(1), np.zeros(1)).set("t_end", 1.0)


def test_each_entry_point_unpacks_what_the_interface_declares_for_its_function():
    for name, arguments in interface.ENTRIES.items():
        function = entries.FUNCTIONS[name]
        code = function.py_func.__code__
        assert [parameter for parameter, _ in arguments] == list(code.co_varnames[:code.co_argcount]), name
        source = unpacking.entry_source(name)
        for _, kind, slot in interface.layout(name):   # each argument read from its own slots
            assert unpacking._READ[kind].format(slot=slot) in source, (name, kind, slot)
        last = interface.layout(name)[-1]
        assert last[2] + (1 if last[1] in interface.NUMBER_KINDS else 3) <= interface.ENTRY_SLOTS
    # a function whose parameters are not the declared ones (here two swapped) has no entry point
    class Swapped:
        def py_func(fn, ys, xs, out, d):
            pass
    with pytest.raises(TypeError, match="declares"):
        unpacking.make_entry("evaluate_points", Swapped)


def test_the_scratch_views_tile_the_scratch_array_the_interface_sizes():
    scratch = unpacking._compile(unpacking.scratch_source(), "scratch", {})   # (the same source, run by Python)
    assert [name for name, _ in interface.SCRATCH] == ["d", "Y", "zn", "pn", "Rn", "Ye", "Re", "pe", "sa", "sb", "sm"]
    resisted = [kernel.state_size(mk, slides, True) for mk in (True, False) for slides in (True, False)]
    for n in (kernel.MOTION_SIZE, kernel.MK_SIZE, kernel.CLASSIC_SIZE, *kernel.SLIDING_SIZES, *resisted):
        work = np.arange(float(kernel.work_size(n)))
        views = scratch(work, n)
        assert np.concatenate([v.ravel() for v in views]).tolist() == work.tolist()
        assert [v.shape for v in views][:5] == [(kernel.D_SIDE + 4,), (n,), (n,), (kernel.PROBE_SIZE,), (3, 3)]


def test_run_arrays_are_the_arrays_every_loop_takes():
    arrays = kernel.run_arrays(kernel.MK_SIZE, 5, 10)
    assert list(arrays) == [name for name, _ in interface.RUN_ARRAYS]
    assert arrays["rows"].shape == (10, kernel.ROW_SIZE) and arrays["K"].shape == (kernel.stage_rows(5), 8)


def test_row_columns_reasons_and_statuses_come_from_the_interface():
    from rollball import trajectory
    from rollball.simulation import describe

    assert len(trajectory.COLUMNS) == 23   # (the 2011 model's, then slip and dissipated)
    # (and the energy rolling resistance, spin friction and air took)
    assert kernel.ROW_SIZE == 28 and (kernel.ROW_ROLLING, kernel.ROW_SPIN, kernel.ROW_AIR) == (25, 26, 27)
    assert trajectory.R == slice(12, 21) and trajectory.CENTER == slice(3, 6) and trajectory.NORMAL_FORCE == 22
    assert trajectory.SLIP_SPEED == kernel.ROW_SLIP == 23 and trajectory.DISSIPATED == kernel.ROW_DISSIPATED == 24
    assert [str(s) for s in trajectory.Status] == [s for s in interface.STATUSES if s != "running"]
    # (then the reasons a flight's landing search stops a run for, set in Python)
    assert [str(r) for r in trajectory.Reason] == list(interface.REASONS) + list(trajectory.FLIGHT_REASONS)
    assert {status for status, _, _ in trajectory.FLIGHT_REASONS.values()} <= {"does_not_fit", "nonfinite"}
    assert interface.reason_name(kernel.R_KINK) == "kink" and interface.reason_name(0) is None
    assert {status for status, _, _ in interface.REASONS.values()} == {"does_not_fit", "nonfinite"}
    failure = trajectory.Failure(trajectory.Reason.ORIENTATION_OVERFLOW, 1.0, 0.5, 0.25, 1.0)
    assert describe(failure, 0.1).startswith("the orientation R overflowed at t = 1 s, (x, y) = (0.5, 0.25)")


def _copy_shipped(tmp_path):
    folder = resources.files("rollball")
    for name in (machine_code.SHIPPED, machine_code.STAMP):
        (tmp_path / name).write_bytes(folder.joinpath(name).read_bytes())
    return tmp_path


def test_shipped_code_with_two_entry_names_swapped_is_not_used(tmp_path):
    _shipped_or_skip()
    folder = _copy_shipped(tmp_path)
    facts = json.loads((folder / machine_code.STAMP).read_text())
    entries = facts["entries"]
    entries["advance"], entries["advance_batch"] = entries["advance_batch"], entries["advance"]
    (folder / machine_code.STAMP).write_text(json.dumps(facts))
    with pytest.raises(machine_code._Unusable, match="entry points"):   # refused before anything is called
        machine_code._shipped(folder)


def test_shipped_code_whose_interface_differs_is_not_used(tmp_path):
    _shipped_or_skip()
    folder = _copy_shipped(tmp_path)
    facts = json.loads((folder / machine_code.STAMP).read_text())
    arguments = facts["interface"]["entries"]["advance"]
    arguments[4], arguments[5] = arguments[5], arguments[4]   # dt and t_end
    (folder / machine_code.STAMP).write_text(json.dumps(facts))
    with pytest.raises(machine_code._Unusable, match="interface"):
        machine_code._shipped(folder)


def test_altered_bitcode_is_rejected_by_its_hash(tmp_path):
    _shipped_or_skip()
    folder = _copy_shipped(tmp_path)
    bitcode = bytearray((folder / machine_code.SHIPPED).read_bytes())
    bitcode[len(bitcode) // 2] ^= 1   # (one constant changed and re-emitted is caught the same way)
    (folder / machine_code.SHIPPED).write_bytes(bytes(bitcode))
    with pytest.raises(machine_code._Unusable, match="SHA-256"):
        machine_code._shipped(folder)


def test_shipped_code_made_from_another_kernel_is_not_used(monkeypatch):
    _shipped_or_skip()
    monkeypatch.setattr(machine_code, "raw_digest", lambda folder=None: "1" * 64)
    monkeypatch.setattr(machine_code, "sources_digest", lambda folder=None: "0" * 64)
    with pytest.raises(machine_code._Unusable, match="kernel"):
        machine_code._shipped()
    monkeypatch.undo()
    monkeypatch.setenv("ROLLBALL_MACHINE_CODE", "numba")
    with pytest.raises(machine_code._Unusable):
        machine_code._shipped()


def test_shipped_code_made_by_another_numba_or_llvmlite_is_not_used(monkeypatch):
    # (a patch release of either: numba's way instead, with its progress line; not an error)
    _shipped_or_skip()
    real = machine_code.stamp
    for key in ("numba", "llvmlite", "triple"):
        monkeypatch.setattr(machine_code, "stamp", lambda shipped=None, key=key: {**real(shipped), key: "other"})
        with pytest.raises(machine_code._Unusable, match=f"made for another {key}"):
            machine_code._shipped()


def _kernel_copy(tmp_path):
    copy = tmp_path / "kernel"
    shutil.copytree(resources.files("rollball").joinpath("kernel"), copy,
                    ignore=shutil.ignore_patterns("__pycache__"))
    return copy


def test_comments_and_docstrings_do_not_change_the_code_digest_and_code_does(tmp_path):
    # a comment-only edit keeps the shipped code in use (no minute-long compile); an edit of one
    # helper in one module changes the digest, and with it the machine code numba's way keys on
    digest = machine_code.sources_digest()
    copy = _kernel_copy(tmp_path)
    physics = copy / "physics.py"
    text = physics.read_text()
    physics.write_text(text + "# a comment at the end\n")
    assert machine_code.sources_digest(copy) == digest
    assert machine_code.raw_digest(copy) != machine_code.raw_digest()
    signature = 'def dexpinv(u1, u2, u3, o1, o2, o3):\n    """'
    edited = text.replace(signature, signature + "Note. ")
    assert edited != text
    physics.write_text(edited)
    assert machine_code.sources_digest(copy) == digest
    assert "DEXPINV_SERIES = 1e-2" in text
    physics.write_text(text.replace("DEXPINV_SERIES = 1e-2", "DEXPINV_SERIES = 2e-2"))
    assert machine_code.sources_digest(copy) != digest


def test_a_docstring_edit_keeps_the_shipped_code_in_use(tmp_path, monkeypatch):
    _shipped_or_skip()
    copy = _kernel_copy(tmp_path)
    module = copy / "dense.py"
    module.write_text(module.read_text().replace('"""Dense output:', '"""Dense output (edited):', 1)
                      + "\n# and a comment\n")
    real = machine_code._digest
    monkeypatch.setattr(machine_code, "_digest", lambda normal, folder=None: real(normal, folder or copy))
    assert machine_code.raw_digest() != json.loads(
        resources.files("rollball").joinpath(machine_code.STAMP).read_text())["sources"]
    bitcode, facts = machine_code._shipped()   # the digest of the code computed, and the same
    assert hashlib.sha256(bitcode).hexdigest() == facts["bitcode"]


def test_shipped_code_llvm_cannot_read_leaves_the_kernel_to_numba(monkeypatch, tmp_path, emit_once):
    bitcode, facts = _shipped_or_skip()

    def unreadable(folder=None):
        return b"not bitcode", {**facts, "bitcode": hashlib.sha256(b"not bitcode").hexdigest()}

    monkeypatch.setattr(machine_code, "_shipped", unreadable)
    # (numba's compile replaced by the shipped code's bitcode: the same code, without the minute)
    monkeypatch.setattr(machine_code, "compile_with_numba", lambda: (bitcode, facts["entries"], facts["calls"]))
    monkeypatch.setattr(machine_code, "_object_path", lambda key: tmp_path / f"kernel-{key}.o")
    monkeypatch.setattr(machine_code, "source", machine_code.source)
    monkeypatch.setattr(machine_code, "refused", machine_code.refused)
    said = []
    monkeypatch.setattr(machine_code, "listeners", [lambda: said.append("compiling the integrator")])
    addresses = machine_code._addresses()
    assert set(addresses) == set(kernel.ENTRIES) and all(addresses.values())
    assert machine_code.source == "numba" and machine_code.refused
    assert said and set(said) == {"compiling the integrator"}   # (the progress line: said once, compile_notice)
    assert len(list(tmp_path.glob("kernel-*.o"))) == 1   # kept for the next process, keyed by the stamp


def test_machine_code_kept_on_disk_is_used_only_whole(tmp_path):
    path = tmp_path / "kernel.o"
    machine_code._write(path, b"machine code")
    assert machine_code._read(path) == b"machine code"
    data = bytearray(path.read_bytes())
    data[-1] ^= 1
    path.write_bytes(bytes(data))
    assert machine_code._read(path) is None
    path.write_bytes(b"")
    assert machine_code._read(path) is None
    assert machine_code._read(tmp_path / "missing.o") is None
    assert machine_code._unpack(machine_code._pack({"advance": "x"}, [], b"code")) == ({"advance": "x"}, [], b"code")
    assert machine_code._unpack(b"\x7fELF no header") is None


def test_the_kernel_package_is_layered_without_import_circles():
    import ast

    layers = ["interface", "lowlevel", "physics", "dense", "recording", "explicit", "collocation", "steps", "bounds",
              "feet", "landing", "flight_rows", "bounces", "events", "unpacking", "loops", "batch", "entries"]
    folder = resources.files("rollball").joinpath("kernel")
    assert sorted(layers + ["__init__"]) == sorted(p.name[:-3] for p in folder.iterdir() if p.name.endswith(".py"))
    for i, name in enumerate(layers):
        tree = ast.parse(folder.joinpath(f"{name}.py").read_text())
        imported = {node.module for node in ast.walk(tree) if isinstance(node, ast.ImportFrom) and node.level == 1}
        assert imported <= set(layers[:i]), (name, imported - set(layers[:i]))


@pytest.mark.parametrize("blocked", ["file", "folder"])
def test_a_corrupt_kernel_file_that_cannot_be_replaced_is_said_once_a_run_not_first_run_only(
        blocked, monkeypatch, tmp_path, capsys, emit_once):
    # A corrupt file the cache cannot replace (read-only, or in a read-only folder: the mode
    # bits decide, root too) made every run compile again, each saying "first run only"
    _shipped_or_skip()
    folder = tmp_path / "cache"
    folder.mkdir()
    monkeypatch.setattr(machine_code, "_object_path", lambda key: folder / f"kernel-{key}.o")
    monkeypatch.setattr(machine_code, "source", machine_code.source)
    monkeypatch.setattr(machine_code, "refused", machine_code.refused)
    said = []
    monkeypatch.setattr(machine_code, "listeners", [lambda: said.append("first run only")])
    machine_code._addresses()
    (path,) = folder.glob("kernel-*.o")
    assert said == ["first run only"]
    data = bytearray(path.read_bytes())
    data[len(data) // 2] ^= 0xFF
    path.write_bytes(bytes(data))
    capsys.readouterr()
    (path if blocked == "file" else folder).chmod(0o444 if blocked == "file" else 0o555)
    try:
        for _ in range(2):   # two runs: each says it once, neither that it is the first
            said.clear()
            addresses = machine_code._addresses()
            assert set(addresses) == set(kernel.ENTRIES) and all(addresses.values())
            lines = capsys.readouterr().err.splitlines()
            assert said == [] and len(lines) == 1, lines
            why = "a read-only file" if blocked == "file" else "its folder is read-only"
            assert lines[0].startswith(f"rollball: warning: the cached machine code of the kernel {path} is corrupt "
                                       f"and cannot be replaced ({why})")
            assert path.read_bytes() == bytes(data) and "first run only" not in lines[0]
    finally:
        folder.chmod(0o700)
        path.chmod(0o644)
    said.clear()
    machine_code._addresses()     # replaceable again: made, kept, and said as the first run
    assert said == ["first run only"] and path.read_bytes() != bytes(data)
    said.clear()
    machine_code._addresses()
    assert said == [] and capsys.readouterr().err == ""


def test_kernel_machine_code_that_cannot_be_kept_says_so_not_first_run_only(monkeypatch, tmp_path, capsys,
                                                                           emit_once):
    _shipped_or_skip()
    folder = tmp_path / "cache"
    folder.mkdir(mode=0o555)
    monkeypatch.setattr(machine_code, "_object_path", lambda key: folder / f"kernel-{key}.o")
    monkeypatch.setattr(machine_code, "source", machine_code.source)
    monkeypatch.setattr(machine_code, "refused", machine_code.refused)
    said = []
    monkeypatch.setattr(machine_code, "listeners", [lambda: said.append("first run only")])
    try:
        machine_code._addresses()
    finally:
        folder.chmod(0o700)
    (line,) = capsys.readouterr().err.splitlines()
    assert said == [] and "cannot be kept" in line and "its folder is read-only" in line and str(folder) in line
    assert list(folder.iterdir()) == []


def test_an_arrays_address_is_its_first_elements():
    """``machine_code._address`` (ctypes' view of a writable buffer, numpy's ``ctypes.data`` for a
    read-only or empty one): the same address for a writable array, a view into one, a read-only
    array and an empty one."""
    a = np.arange(12.0).reshape(3, 4)
    frozen = a.copy()
    frozen.flags.writeable = False
    for array in (a, a[1:], a[:, :2].copy(), frozen, a[:0], np.zeros(0, dtype=np.int64)):
        assert machine_code._address(array, array.flags.writeable) == array.ctypes.data
