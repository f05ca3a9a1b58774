"""Where the damage audits overwrite a result file: 64 bytes of 0xff at every 4 KiB
(test_audit_results.py for load_result, test_audit_leftovers.py for plot and export).

Most of a result file is the raw data of its numeric datasets (the beam's surface modes,
the chunks of the sampled values). Damage that lies wholly inside one dataset's raw data
gives every place of that dataset the same fault: some of its values become 0xff bytes
(NaN, -1), with the file's structure intact. Such places are kept once per dataset; every
place that touches the file's metadata (superblock, object headers, attributes, B-trees,
heaps) or free space is kept. The extents are read with h5py from the undamaged file."""

from __future__ import annotations

import os

import h5py

STRIDE, LENGTH = 4096, 64        # [bytes]: a place every STRIDE bytes, LENGTH bytes of 0xff at each


def raw_extents(path) -> list[tuple[str, int, int]]:
    """(dataset name, first byte, end byte) of the raw data of every numeric dataset of
    ``path`` stored unfiltered (contiguous, or each chunk of a chunked one)."""
    extents = []

    def visit(name, obj):
        if not isinstance(obj, h5py.Dataset) or obj.dtype.kind not in "iuf" or obj.compression or obj.fletcher32:
            return
        if obj.chunks is None:
            offset = obj.id.get_offset()
            if offset is not None:
                extents.append((name, offset, offset + obj.id.get_storage_size()))
            return
        for i in range(obj.id.get_num_chunks()):
            info = obj.id.get_chunk_info(i)
            extents.append((name, info.byte_offset, info.byte_offset + info.size))

    with h5py.File(path, "r") as f:
        f.visititems(visit)
    return extents


def damage_places(path) -> list[int]:
    """The byte offsets of the 4 KiB grid of ``path`` to damage: all but the second and
    later places of a dataset lying wholly inside its raw data."""
    extents = raw_extents(path)
    size = os.path.getsize(path)
    places, seen = [], set()
    for offset in range(0, size, STRIDE):
        inside = [name for name, start, end in extents if start <= offset and offset + LENGTH <= end]
        if inside:
            if inside[0] in seen:
                continue
            seen.add(inside[0])
        places.append(offset)
    return places


def damaged(data: bytes, offset: int) -> bytes:
    """``data`` with LENGTH bytes of 0xff from ``offset`` on."""
    return data[:offset] + b"\xff" * LENGTH + data[offset + LENGTH:]


__all__ = ["LENGTH", "STRIDE", "damage_places", "damaged", "raw_extents"]
