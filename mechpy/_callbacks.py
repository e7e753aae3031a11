"""Low-level callbacks: a C function handed over from Python.

The one place that reads a ctypes function pointer, a ``scipy.LowLevelCallable``
or a numba ``cfunc`` as ``(address, user_data)`` for the C core.  Both
:mod:`mechpy.integrate` (right-hand sides) and :mod:`mechpy.scenes` (a rigid
body's torque) use it; it imports neither.
"""
from __future__ import annotations

import ctypes

__all__ = ["c_address", "check_signature"]


def c_address(obj):
    """(address, user_data) of a low-level C callback, or None if obj is not one."""
    # scipy.LowLevelCallable: a tuple (capsule, function, user_data); the
    # capsule's pointer is the function, its context the user data
    if type(obj).__name__ == "LowLevelCallable" and isinstance(obj, tuple):
        cap = tuple.__getitem__(obj, 0)
        api = ctypes.pythonapi
        api.PyCapsule_GetName.restype = ctypes.c_char_p
        api.PyCapsule_GetName.argtypes = [ctypes.py_object]
        api.PyCapsule_GetPointer.restype = ctypes.c_void_p
        api.PyCapsule_GetPointer.argtypes = [ctypes.py_object, ctypes.c_char_p]
        api.PyCapsule_GetContext.restype = ctypes.c_void_p
        api.PyCapsule_GetContext.argtypes = [ctypes.py_object]
        sig = api.PyCapsule_GetName(cap)
        check_signature(sig.decode() if sig else "")
        return api.PyCapsule_GetPointer(cap, sig), api.PyCapsule_GetContext(cap)
    # numba cfunc
    if type(obj).__name__ == "CFunc" and hasattr(obj, "address"):
        return obj.address, None
    # ctypes function pointer
    if isinstance(obj, ctypes._CFuncPtr):
        if obj.argtypes is not None and len(obj.argtypes) != 4:
            raise TypeError("a C callback must have the signature "
                            "void f(double t, const double *y, double *dydt, void *user_data)")
        addr = ctypes.cast(obj, ctypes.c_void_p).value
        if not addr:
            raise ValueError("the C callback is a NULL function pointer")
        return addr, None
    return None


def check_signature(sig: str):
    s = sig.replace(" ", "")
    ok = s.startswith("void(double,") and s.count(",") == 3 and "double*" in s
    if not ok:
        raise TypeError(f"LowLevelCallable signature {sig!r} does not match "
                        "'void (double, double const *, double *, void *)'")
