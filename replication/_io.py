"""Atomic file writes: every output of this package is written whole or not at all."""
from __future__ import annotations

import os
from pathlib import Path


def write_atomic(path, data: bytes | str) -> None:
    """Write ``data`` (``str`` as UTF-8) to ``path`` through a temporary file and an atomic rename.

    A reader never sees a half-written file, and an interrupted write leaves the old file (or none) in place.
    """
    path = Path(path)
    if isinstance(data, str):
        data = data.encode("utf-8")
    tmp = path.with_name(path.name + ".part")
    try:
        tmp.write_bytes(data)
        os.replace(tmp, path)
    finally:
        if tmp.exists():
            tmp.unlink()


def png_bytes(fig, dpi=None) -> bytes:
    """A matplotlib figure as PNG bytes, cropped to its content, without the (version-dependent) software tag."""
    import io

    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", bbox_inches="tight", metadata={"Software": None},
                **({} if dpi is None else {"dpi": dpi}))
    return buffer.getvalue()

