"""How the kernel is compiled (numba's options for its three kinds of function) and the few
LLVM-level operations it needs: an array's data pointer, a call of the landscape's code by
its address, an address read as a pointer."""

from __future__ import annotations

from llvmlite import ir
from numba import njit, types
from numba.extending import intrinsic

from .interface import FLOAT, LANDSCAPE_ARGUMENTS, LANDSCAPE_RECORD_CODE, LANDSCAPE_RECORD_VALUES, POINTER

# The landscape's code as a C function, from its declaration (interface.LANDSCAPE_ARGUMENTS).
LANDSCAPE_SIGNATURE = types.void(*[{FLOAT: types.float64, POINTER: types.CPointer(types.float64)}[kind]
                                   for _, kind in LANDSCAPE_ARGUMENTS])

# numpy's error model: a division by zero gives inf/nan (caught by the checks) instead of
# a branch and an exception on every division. Nothing here allocates, so it runs without
# numba's reference counting (_nrt=False): the counting of arrays handed between the helpers
# would cost as much as a stage.
#
# What is inlined where, and why (numba's cold compile is what a machine without the shipped
# code waits for once, and what kernel_build takes; the step's speed is the ratio to
# hand-written C):
# - JIT, numba's own inlining (the helper's code is copied into every caller before typing):
#   the small per-stage and per-step helpers (dynamics, combine, rodrigues, the finiteness
#   checks, step_events, accept, record, ...). Each copy costs compile time, so JIT helpers
#   are kept small and called from few places.
# - STEP, compiled once as a function of its own and inlined by LLVM (forceinline) into the
#   loops that call it: the explicit step, one per state layout (``_trial_step``), which holds
#   most of the code. Inlined by numba it was copied into every loop; called, a step cost a
#   fifth more.
# - COLD, compiled once and called: what runs once per run, per recorded row or per event
#   (start, the event location, the last valid state), the implicit step, whose stage
#   iteration outweighs a call, the step of the searches inside a step (``search_step``), and
#   the fixed-step loop ``advance``, which the sweeps' batch loop calls once per chunk of steps.
#   (numba still compiles a called function again into each caller's machine code: LLVM's share
#   of a cold compile grows with how many loops reach a function, not with how often it runs.)
# One signature each: a constant bool or int passed to a compiled function makes numba compile
# it anew for that constant, so flags passed to COLD functions are floats (EXPLICIT/IMPLICIT,
# the event kinds) or read from the arrays (shape_of).
# No numba disk cache (cache=False): it watches only the file a function is defined in, so a
# helper changed in one module would leave stale code in its callers' cache entries. The
# compiled kernel is kept instead as machine code keyed by a digest of the whole package
# (machine_code.py).
JIT = njit(cache=False, nogil=True, error_model="numpy", inline="always", fastmath={"contract"},
           _nrt=False)
COLD = njit(cache=False, nogil=True, error_model="numpy", fastmath={"contract"}, _nrt=False)
STEP = njit(cache=False, nogil=True, error_model="numpy", forceinline=True, fastmath={"contract"}, _nrt=False)
# EXACT: no contraction into fused multiply-adds, so that a function computes what the same
# formula in numpy computes, bit for bit (the closest surface points of a flight, ``closest_points``).
EXACT = njit(cache=False, nogil=True, error_model="numpy", _nrt=False)
# INLINE_EXACT: EXACT's arithmetic, inlined by numba where it is called (no compile of its own).
INLINE_EXACT = njit(cache=False, nogil=True, error_model="numpy", inline="always", _nrt=False)


@intrinsic
def data_pointer(typingctx, array):
    """The data pointer of an array, without the reference counting of ``array.ctypes``
    (which costs more than the landscape call itself). The caller keeps the array alive."""
    def codegen(context, builder, signature, args):
        return context.make_array(signature.args[0])(context, builder, args[0]).data
    return types.CPointer(array.dtype)(array), codegen


@intrinsic
def landscape(typingctx, address, x, y, out):
    """Call the landscape whose record is at ``address`` (interface: the code's address, then
    the parameters' values): its code (LANDSCAPE_SIGNATURE) gives f and its derivatives at
    (x, y) into out[0:6]. Addresses, not a function object, so that the kernel's compiled code
    holds nothing of this process and can be shipped."""
    def codegen(context, builder, signature, args):
        double, word = ir.DoubleType(), ir.IntType(64)
        code = ir.FunctionType(ir.VoidType(), [double, double, double.as_pointer(), double.as_pointer()])
        record = builder.inttoptr(args[0], word.as_pointer())
        function = builder.load(builder.gep(record, [ir.Constant(word, LANDSCAPE_RECORD_CODE)]))
        values = builder.bitcast(builder.gep(record, [ir.Constant(word, LANDSCAPE_RECORD_VALUES)]),
                                 double.as_pointer())
        builder.call(builder.inttoptr(function, code.as_pointer()), [args[1], args[2], values, args[3]])
        return context.get_dummy_value()
    return types.void(types.int64, types.float64, types.float64, types.CPointer(types.float64)), codegen


def _pointer_to(dtype):
    @intrinsic
    def pointer(typingctx, address):
        """The address (an int64) as a pointer to numbers of this dtype."""
        def codegen(context, builder, signature, args):
            return builder.inttoptr(args[0], context.get_value_type(signature.return_type))
        return types.CPointer(dtype)(types.int64), codegen
    return pointer


float_pointer, int_pointer = _pointer_to(types.float64), _pointer_to(types.int64)


@intrinsic
def as_floats(typingctx, pointer):
    """The same memory as a pointer to float64 (the entry points' float arguments)."""
    def codegen(context, builder, signature, args):
        return builder.bitcast(args[0], context.get_value_type(signature.return_type))
    return types.CPointer(types.float64)(pointer), codegen
