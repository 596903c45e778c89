"""lsmorph: fill the slices between the drawn slices of a label volume by level-set
metamorphosis, every label at once, in memory (liblsmorph through ctypes).

    import lsmorph
    filled = lsmorph.fill(labels, spacing=(0.8, 0.8, 2.5))      # NumPy in, NumPy out

``fill`` is ``lsmorph fill`` without the files: the same rules, options and result,
voxel for voxel.  ``reconstruct`` turns a stack of binary masks into the signed distance
volume of ``lsmorph reconstruct``.  Errors raise ``lsmorph.Error`` (a RuntimeError with
the library's message and ``status``).

The library is found as $LSMORPH_LIBRARY, else liblsmorph.so beside this file (a build's
build/python/lsmorph), else where ``make install`` put it, else on the system's path.
"""
import ctypes
import ctypes.util
import os
import re

import numpy as np

__all__ = ["fill", "reconstruct", "Error", "version"]

_DTYPES = {np.dtype(t): k for k, t in enumerate(
    (np.uint8, np.int8, np.uint16, np.int16, np.uint32, np.int32, np.uint64, np.int64))}


class Error(RuntimeError):
    """A failure reported by liblsmorph: ``status`` is its code, the message its text."""

    def __init__(self, status, message):
        super().__init__(message)
        self.status = status


class _Options(ctypes.Structure):
    _fields_ = [("size", ctypes.c_size_t), ("method", ctypes.c_char_p),
                ("interp", ctypes.c_char_p), ("ends", ctypes.c_char_p),
                ("align", ctypes.c_char_p), ("scheme", ctypes.c_char_p),
                ("time", ctypes.c_char_p), ("cfl", ctypes.c_double),
                ("max_iter", ctypes.c_int), ("reinit_every", ctypes.c_int),
                ("reinit_iters", ctypes.c_int), ("particles_per_cell", ctypes.c_int),
                ("seed", ctypes.c_uint64), ("threads", ctypes.c_int),
                ("backend", ctypes.c_char_p), ("device", ctypes.c_int),
                ("motion", ctypes.c_char_p)]


_TEXT = ("method", "interp", "ends", "align", "motion", "scheme", "time", "backend")
_NUMBERS = ("cfl", "max_iter", "reinit_every", "reinit_iters", "particles_per_cell", "seed",
            "threads", "device")


def _find_library():
    here = os.path.dirname(os.path.abspath(__file__))
    candidates = [os.environ.get("LSMORPH_LIBRARY"), os.path.join(here, "liblsmorph.so")]
    try:
        from . import _installed
        candidates.append(_installed.LIBRARY)
    except ImportError:
        pass
    candidates.append(ctypes.util.find_library("lsmorph"))
    for path in candidates:
        if path and (os.path.exists(path) or not os.path.isabs(path)):
            try:
                return ctypes.CDLL(path)
            except OSError:
                continue
    raise ImportError("lsmorph: liblsmorph.so not found (build it with make, or set LSMORPH_LIBRARY)")


_lib = _find_library()
_lib.lsmorph_options_default.argtypes = [ctypes.POINTER(_Options)]
_lib.lsmorph_version.restype = ctypes.c_char_p
_lib.lsmorph_fill.restype = ctypes.c_int
_lib.lsmorph_fill.argtypes = [
    ctypes.c_void_p, ctypes.c_int, ctypes.POINTER(ctypes.c_size_t), ctypes.POINTER(ctypes.c_double),
    ctypes.c_int, ctypes.POINTER(ctypes.c_size_t), ctypes.c_size_t, ctypes.POINTER(ctypes.c_int64),
    ctypes.c_size_t, ctypes.POINTER(_Options), ctypes.POINTER(ctypes.c_size_t), ctypes.c_char_p,
    ctypes.c_size_t]
_lib.lsmorph_reconstruct_count.restype = ctypes.c_size_t
_lib.lsmorph_reconstruct_count.argtypes = [ctypes.POINTER(ctypes.c_double), ctypes.c_size_t,
                                           ctypes.c_double]
_lib.lsmorph_reconstruct.restype = ctypes.c_int
_lib.lsmorph_reconstruct.argtypes = [
    ctypes.c_void_p, ctypes.c_size_t, ctypes.c_size_t, ctypes.c_size_t,
    ctypes.POINTER(ctypes.c_double), ctypes.c_double, ctypes.c_double, ctypes.c_double,
    ctypes.POINTER(_Options), ctypes.c_void_p, ctypes.c_size_t, ctypes.c_char_p, ctypes.c_size_t]


def version():
    """liblsmorph's version ("0.1.0")."""
    return _lib.lsmorph_version().decode()


def _options(options):
    o = _Options()
    _lib.lsmorph_options_default(ctypes.byref(o))
    keep = []  # the encoded strings must outlive the call
    for name, value in options.items():
        if name in _TEXT:
            keep.append(str(value).encode())
            setattr(o, name, keep[-1])
        elif name in _NUMBERS:
            setattr(o, name, float(value) if name == "cfl" else int(value))
        else:
            raise TypeError("lsmorph: unknown option %r (options: %s)" % (name, ", ".join(_TEXT + _NUMBERS)))
    return o, keep


def _check(status, message, turned=False):
    """Raises Error for a failed call; turned: the library saw the axes reversed (a C-ordered
    array as [k, j, i]), so its axis names are turned back into the caller's."""
    if status != 0:
        text = message.value.decode(errors="replace") or "lsmorph: error %d" % status
        if turned:
            text = re.sub(r"\b(across|along|--axis) ([ijk])\b",
                          lambda m: "%s %s" % (m.group(1), "kji"["ijk".index(m.group(2))]), text)
        raise Error(status, text)


def fill(labels, spacing=(1.0, 1.0, 1.0), axis=None, slices=None, fill_labels=None, out=None,
         **options):
    """The label volume ``labels`` (a 3D integer array indexed [i, j, k], any memory order) with
    the slices between its drawn slices filled, every label at once, as ``lsmorph fill`` fills
    a NIfTI or NRRD volume.

    spacing      the physical voxel size along i, j, k
    axis         0, 1 or 2 (i, j, k): the axis the drawn slices lie across; None: the axis of
                 the largest spacing, the last on ties
    slices       the drawn slices (indices from 0); None: every slice holding a label, plus
                 one typical step beyond the first and the last, taken as drawn empty
    fill_labels  the labels to fill; None: every non-zero value (the others are kept)
    out          the array to fill (the result); None: a copy of ``labels``; ``labels``
                 itself fills it in place
    options      method, interp, ends (default "halfway"), align, motion, scheme, time, cfl,
                 max_iter, reinit_every, reinit_iters, particles_per_cell, seed, threads, backend, device

    Returns the filled array (``out``).  The drawn slices and the labels not filled come back
    exactly; each voxel between gets the label it lies deepest inside, or 0.
    """
    a = np.asarray(labels)
    if a.ndim != 3:
        raise ValueError("lsmorph.fill: labels must be 3D, not %dD" % a.ndim)
    if a.size == 0:
        raise ValueError("lsmorph.fill: labels has no voxels (shape %s)" % (a.shape,))
    if a.dtype.kind not in "iu":
        raise TypeError("lsmorph.fill: labels must be integers, not %s (labels stored as "
                        "floats: labels.astype(int) after checking they are whole)" % a.dtype)
    native = a.dtype.newbyteorder("=")
    if out is None:
        out = np.array(a, dtype=native, order="K", copy=True)
    elif out is not a:
        if out.shape != a.shape or out.dtype != native:
            raise ValueError("lsmorph.fill: out must have the shape and (native) type of labels")
        out[...] = a
    if out.dtype != native:
        raise ValueError("lsmorph.fill: to fill in place, labels must be in the machine's byte order")
    spacing = [float(s) for s in (spacing if np.ndim(spacing) else (spacing,) * 3)]
    if len(spacing) != 3:
        raise ValueError("lsmorph.fill: spacing takes three lengths (i, j, k)")
    if axis is None:  # the CLI's default: the largest spacing, the last on ties
        axis = 0
        for a in (1, 2):
            if spacing[a] >= spacing[axis] * (1 - 1e-6):
                axis = a
    if int(axis) not in (0, 1, 2):
        raise ValueError("lsmorph.fill: axis must be 0, 1, 2 or None")
    # liblsmorph reads i fastest: a Fortran-ordered array as it is, a C-ordered one as the
    # volume [k, j, i] (no copy either way), anything else through a Fortran-ordered copy
    work = out if out.flags.f_contiguous or out.flags.c_contiguous else np.asfortranarray(out)
    if work.flags.f_contiguous:
        n, sp, ax = work.shape, spacing, int(axis)
    else:
        n, sp, ax = work.shape[::-1], spacing[::-1], 2 - int(axis)
    drawn = None if slices is None else np.ascontiguousarray(slices, dtype=np.uintp)
    chosen = None if fill_labels is None else np.ascontiguousarray(fill_labels, dtype=np.int64)
    o, keep = _options(options)
    message = ctypes.create_string_buffer(1024)
    filled = ctypes.c_size_t(0)
    status = _lib.lsmorph_fill(
        work.ctypes.data, _DTYPES[np.dtype(work.dtype)], (ctypes.c_size_t * 3)(*n),
        (ctypes.c_double * 3)(*sp), ax,
        None if drawn is None else drawn.ctypes.data_as(ctypes.POINTER(ctypes.c_size_t)),
        0 if drawn is None else drawn.size,
        None if chosen is None else chosen.ctypes.data_as(ctypes.POINTER(ctypes.c_int64)),
        0 if chosen is None else chosen.size, ctypes.byref(o), ctypes.byref(filled), message,
        len(message))
    _check(status, message, not work.flags.f_contiguous)
    if work is not out:
        out[...] = work
    return out


def reconstruct(masks, heights=None, spacing=1.0, pixel_size=(1.0, 1.0), dz=None, **options):
    """The signed distance volume (float32, negative inside, physical units) that
    ``lsmorph reconstruct`` makes of the binary masks ``masks`` (slices, rows, columns;
    non-zero inside), and its slices' heights.

    heights      one height per mask, increasing; None: ``spacing`` apart from 0
    pixel_size   the width and height of a pixel (one number for square pixels)
    dz           the output spacing; None: the smaller pixel side
    options      as for ``fill`` (``ends`` default "auto")
    """
    m = np.ascontiguousarray(np.asarray(masks) != 0, dtype=np.uint8)  # non-zero: inside
    if m.ndim != 3 or m.shape[0] < 2:
        raise ValueError("lsmorph.reconstruct: masks must be a stack of at least two 2D slices")
    z = np.ascontiguousarray(np.arange(m.shape[0]) * float(spacing) if heights is None else heights,
                             dtype=np.float64)
    if z.shape != (m.shape[0],):
        raise ValueError("lsmorph.reconstruct: one height per mask")
    px = pixel_size if np.ndim(pixel_size) else (pixel_size, pixel_size)
    step = float(dz) if dz is not None else min(float(px[0]), float(px[1]))
    if dz is not None and not (step > 0.0 and np.isfinite(step)):
        raise ValueError("lsmorph.reconstruct: dz must be a positive length, not %r" % (dz,))
    zp = z.ctypes.data_as(ctypes.POINTER(ctypes.c_double))
    count = _lib.lsmorph_reconstruct_count(zp, z.size, step)
    out = np.empty((count, m.shape[1], m.shape[2]), np.float32)
    o, keep = _options(options)
    message = ctypes.create_string_buffer(1024)
    status = _lib.lsmorph_reconstruct(m.ctypes.data, m.shape[0], m.shape[2], m.shape[1], zp,
                                      float(px[0]), float(px[1]), step, ctypes.byref(o),
                                      out.ctypes.data, count, message, len(message))
    _check(status, message)
    return out, z[0] + step * np.arange(count)
