"""A minimal Phantom .cine writer for the tests (8-bit grey, uncompressed), following the file layout of the
Phantom documentation as ``pims.Cine`` reads it: CINEFILEHEADER, BITMAPINFOHEADER, SETUP (with the frame
rate), tagged blocks (frame times, exposures), the table of image offsets, then per image its annotation
block and the rows stored bottom-up.  No real camera file could be had here; this checks the reading path."""
from __future__ import annotations

import struct

import numpy as np


def write_cine(path, frames: np.ndarray, fps: float) -> None:
    import pims.cine as pc

    n, h, w = frames.shape
    fields = pc.SETUP_FIELDS
    fmt = "<" + "".join(f for _, f in fields)
    setup_len = struct.calcsize(fmt)
    values = []
    for name, f in fields:
        count = struct.calcsize("<" + f)
        parts = struct.unpack("<" + f, bytes(count))  # zeros of the right types
        if name == "length":
            parts = (setup_len,)
        elif name == "frame_rate":
            parts = (int(round(fps)),)
        elif name == "software_version":
            parts = (10 ** 6,)  # newer than every version pims knows: the whole setup is kept
        values.extend(parts)
    setup = struct.pack(fmt, *values)
    off_header, off_bitmap, off_setup = 0, 44, 84
    tags = (struct.pack("<IHH", 8 + 8 * n, 1002, 1) + struct.pack(f"<{n}Q", *[(k << 32) for k in range(n)])
            + struct.pack("<IHH", 8 + 4 * n, 1003, 0) + struct.pack(f"<{n}I", *([2 ** 31] * n)))
    off_offsets = off_setup + setup_len + len(tags)
    first_image = off_offsets + 8 * n
    image_bytes = 8 + h * w
    offsets = [first_image + k * image_bytes for k in range(n)]
    header = struct.pack("<2sHHHiIiIIIIQ", b"CI", 44, 0, 1, 0, n, 0, n, off_bitmap, off_setup, off_offsets, 0)
    bitmap = struct.pack("<IiiHHIIiiII", 40, w, h, 1, 8, 0, h * w, 0, 0, 0, 0)
    with open(path, "wb") as fh:
        fh.write(header + bitmap + setup + tags + struct.pack(f"<{n}Q", *offsets))
        for f in frames:
            fh.write(struct.pack("<II", 8, h * w) + np.ascontiguousarray(f[::-1], np.uint8).tobytes())
