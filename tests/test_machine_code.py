"""The kernel's machine code: made from the shipped LLVM code where it fits, else by numba;
its arguments packed by name and kind; what is kept on disk checked before it is used."""

import numpy as np
import pytest

from rollball import kernel, machine_code
from rollball.landscape import landscape_for


def _points(xs, ys):
    return machine_code.Arguments("evaluate_points", landscape_for("x^2 + 3*y").compiled.address, xs, ys,
                                  np.empty((6, len(xs))), np.empty(6))


def test_arguments_run_the_kernel_and_one_can_be_changed_by_name():
    call = _points(np.array([1.0, 2.0]), np.array([0.5, -1.0]))
    call()
    assert call.kept[3][0].tolist() == [2.5, 1.0]   # f = x^2 + 3y
    call.set("xs", np.array([3.0, 0.0]))
    call()
    assert call.kept[3][0].tolist() == [10.5, -3.0] and call.kept[3][1].tolist() == [6.0, 0.0]   # f, f_x


@pytest.mark.parametrize("xs, words", [(np.array([1, 2]), "xs must be a C-contiguous vector of float64"),
                                       (np.zeros((2, 2)), "xs must be a C-contiguous vector of float64"),
                                       (np.zeros(4)[::2], "xs must be a C-contiguous vector of float64")])
def test_an_array_of_the_wrong_kind_is_refused_by_name(xs, words):
    with pytest.raises(TypeError, match=words):
        _points(xs, np.zeros(2))


def test_a_wrong_number_of_arguments_is_refused():
    with pytest.raises(TypeError, match="5 arguments expected, 4 given"):
        machine_code.Arguments("evaluate_points", 0, np.zeros(1), np.zeros(1), np.zeros((6, 1)))


def test_every_entry_point_packs_its_functions_parameters_into_the_slots():
    for name, (_, kinds) in kernel.ENTRIES.items():
        parameters = getattr(kernel, name).py_func.__code__.co_argcount
        slots = sum(1 if kind in ("int", "float", "address") else 3 for kind in kinds.split())
        assert len(kinds.split()) == parameters and slots <= kernel.ENTRY_SLOTS, name


def test_shipped_code_made_from_another_kernel_is_not_used(monkeypatch):
    assert machine_code._shipped() is not None
    monkeypatch.setattr(machine_code, "sources_digest", lambda: "0" * 64)
    assert machine_code._shipped() is None
    monkeypatch.undo()
    monkeypatch.setenv("ROLLBALL_MACHINE_CODE", "numba")
    assert machine_code._shipped() is None


def test_shipped_code_llvm_cannot_read_leaves_the_kernel_to_numba(monkeypatch):
    class Compiled:
        address = 1234

    monkeypatch.setattr(machine_code, "_shipped", lambda: (b"not bitcode", {"advance": "x"}, []))
    monkeypatch.setattr(machine_code, "numba_entry", lambda name: Compiled)
    monkeypatch.setattr(machine_code, "source", machine_code.source)
    assert machine_code._addresses() == {name: 1234 for name in kernel.ENTRIES}
    assert machine_code.source == "numba"


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
