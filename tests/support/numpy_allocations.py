"""Counting numpy's data allocations: a context manager that installs a numpy memory
handler (NEP 49, ``PyDataMem_SetHandler`` from numpy's C-API table, through ctypes)
which counts every malloc, calloc and realloc of an array's data and passes it on to
the C library. Views and Python objects (scalars, tuples) allocate no array data and
are not counted.

    with NumpyAllocations() as count:
        work()
    count.n        # array data buffers allocated meanwhile
    count.sizes    # their sizes [bytes]
"""

from __future__ import annotations

import ctypes

import numpy as np

_MALLOC = ctypes.CFUNCTYPE(ctypes.c_void_p, ctypes.c_void_p, ctypes.c_size_t)
_CALLOC = ctypes.CFUNCTYPE(ctypes.c_void_p, ctypes.c_void_p, ctypes.c_size_t, ctypes.c_size_t)
_REALLOC = ctypes.CFUNCTYPE(ctypes.c_void_p, ctypes.c_void_p, ctypes.c_void_p, ctypes.c_size_t)
_FREE = ctypes.CFUNCTYPE(None, ctypes.c_void_p, ctypes.c_void_p, ctypes.c_size_t)
SET_HANDLER = 304      # index of PyDataMem_SetHandler in numpy's C-API table (numpy >= 1.22)


class _Allocator(ctypes.Structure):
    _fields_ = [("ctx", ctypes.c_void_p), ("malloc", _MALLOC), ("calloc", _CALLOC), ("realloc", _REALLOC),
                ("free", _FREE)]


class _Handler(ctypes.Structure):
    _fields_ = [("name", ctypes.c_char * 127), ("version", ctypes.c_uint8), ("allocator", _Allocator)]


_libc = ctypes.CDLL(None)
_libc.malloc.restype, _libc.malloc.argtypes = ctypes.c_void_p, [ctypes.c_size_t]
_libc.calloc.restype, _libc.calloc.argtypes = ctypes.c_void_p, [ctypes.c_size_t, ctypes.c_size_t]
_libc.realloc.restype, _libc.realloc.argtypes = ctypes.c_void_p, [ctypes.c_void_p, ctypes.c_size_t]
_libc.free.restype, _libc.free.argtypes = None, [ctypes.c_void_p]


def _set_handler():
    """numpy's PyDataMem_SetHandler(capsule) -> previous capsule."""
    api = ctypes.pythonapi
    api.PyCapsule_GetPointer.restype, api.PyCapsule_GetPointer.argtypes = ctypes.c_void_p, [ctypes.py_object,
                                                                                           ctypes.c_char_p]
    from numpy._core import _multiarray_umath
    table = ctypes.cast(api.PyCapsule_GetPointer(_multiarray_umath._ARRAY_API, None),
                        ctypes.POINTER(ctypes.c_void_p))
    return ctypes.PYFUNCTYPE(ctypes.py_object, ctypes.py_object)(table[SET_HANDLER])


class NumpyAllocations:
    """Context manager counting numpy array-data allocations: ``n``, ``sizes`` [bytes] (module docstring)."""

    def __init__(self):
        self.sizes = []

        def malloc(ctx, size):
            self.sizes.append(size)
            return _libc.malloc(size)

        def calloc(ctx, nelem, elsize):
            self.sizes.append(nelem * elsize)
            return _libc.calloc(nelem, elsize)

        def realloc(ctx, ptr, size):
            self.sizes.append(size)
            return _libc.realloc(ptr, size)

        def free(ctx, ptr, size):
            _libc.free(ptr)

        self._callbacks = (_MALLOC(malloc), _CALLOC(calloc), _REALLOC(realloc), _FREE(free))
        self._handler = _Handler(b"counting", 1, _Allocator(None, *self._callbacks))
        api = ctypes.pythonapi
        api.PyCapsule_New.restype, api.PyCapsule_New.argtypes = ctypes.py_object, [ctypes.c_void_p, ctypes.c_char_p,
                                                                                  ctypes.c_void_p]
        self._capsule = api.PyCapsule_New(ctypes.addressof(self._handler), b"mem_handler", None)
        self._set = _set_handler()
        for obj in (*self._callbacks, self._handler, self._capsule):   # arrays made here may be
            api.Py_IncRef(ctypes.py_object(obj))                        # freed at exit: keep them

    @property
    def n(self) -> int:
        return len(self.sizes)

    def __enter__(self):
        self.sizes = []
        self._previous = self._set(self._capsule)
        assert np._core.multiarray.get_handler_name() == "counting"
        return self

    def __exit__(self, *exc):
        self._set(self._previous)
        return False
