"""openpi's wire format: msgpack with numpy arrays as tagged maps, and its image preprocessing.

Byte-compatible with ``openpi_client.msgpack_numpy`` (an ndarray is ``{b"__ndarray__": True,
b"data": bytes, b"dtype": dtype.str, b"shape": shape}``, a numpy scalar ``{b"__npgeneric__": True,
b"data": item, b"dtype": dtype.str}``) and ``openpi_client.image_tools.resize_with_pad``, without
its ``numpy<2`` pin. The test suite checks both against the real package when it is installed.
"""

from __future__ import annotations

import msgpack
import numpy as np


def _pack(obj):
    if isinstance(obj, (np.ndarray, np.generic)) and obj.dtype.kind in ("V", "O", "c"):
        raise ValueError(f"unsupported dtype for the openpi wire format: {obj.dtype}")
    if isinstance(obj, np.ndarray):
        return {b"__ndarray__": True, b"data": obj.tobytes(), b"dtype": obj.dtype.str, b"shape": obj.shape}
    if isinstance(obj, np.generic):
        return {b"__npgeneric__": True, b"data": obj.item(), b"dtype": obj.dtype.str}
    return obj


def _unpack(obj):
    if b"__ndarray__" in obj:
        return np.ndarray(buffer=obj[b"data"], dtype=np.dtype(obj[b"dtype"]), shape=obj[b"shape"])
    if b"__npgeneric__" in obj:
        return np.dtype(obj[b"dtype"]).type(obj[b"data"])
    return obj


def packb(obj) -> bytes:
    return msgpack.packb(obj, default=_pack)


def unpackb(data: bytes):
    return msgpack.unpackb(data, object_hook=_unpack)


def resize_with_pad(images: np.ndarray, height: int, width: int) -> np.ndarray:
    """Letterbox (..., H, W, C) uint8 images into height x width (bilinear, zero padding, centred),
    as ``tf.image.resize_with_pad`` / openpi's PIL version (same integer sizes and offsets)."""
    from PIL import Image

    if images.shape[-3:-1] == (height, width):
        return images
    shape = images.shape
    flat = images.reshape(-1, *shape[-3:])
    out = []
    for im in flat:
        pil = Image.fromarray(im)
        w0, h0 = pil.size
        ratio = max(w0 / width, h0 / height)
        rh, rw = int(h0 / ratio), int(w0 / ratio)
        resized = pil.resize((rw, rh), resample=Image.BILINEAR)
        canvas = Image.new(resized.mode, (width, height), 0)
        canvas.paste(resized, (max(0, int((width - rw) / 2)), max(0, int((height - rh) / 2))))
        out.append(np.asarray(canvas))
    return np.stack(out).reshape(*shape[:-3], height, width, shape[-1])
