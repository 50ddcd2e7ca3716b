"""A NumPy ``.npz`` archive read without trusting it: nothing is decompressed or allocated past a bound.

``np.load`` decompresses a member whole before anyone can look at its shape: a 1.1 MB archive of
zeros unpacks to 819 MB, and a 0-d text array takes four bytes a character. Here, before any member
is opened, the archive's directory is checked (a few members, a small directory: a 54 MB directory of
600,000 empty members takes zipfile 340 MB and 3 s to list). Each member's ``.npy`` header, read
from the first bytes of its stream (at most :data:`MAX_NPY_HEADER` bytes), says its dtype and shape,
so the caller judges them before anything else is read; :meth:`Archive.read` refuses an array over
the bound it is given before allocating it, reads it in chunks into that one array, and reads to the
member's end so that zipfile checks its CRC. Nothing is unpickled: a dtype that holds Python objects
is refused from its header, and only stored and deflated members (``np.savez``,
``np.savez_compressed``) are read.
"""

from __future__ import annotations

import io
import math
import struct
import zipfile
from dataclasses import dataclass
from typing import BinaryIO

import numpy as np

#: The longest ``.npy`` header parsed: numpy's own limit for a header it parses safely (ours are 128 bytes).
MAX_NPY_HEADER = 10_000
#: Members an archive may list, and bytes its directory may take (three members take about 300).
MAX_MEMBERS = 16
MAX_DIRECTORY_BYTES = 16_384
#: Bytes read from a member at a time.
CHUNK = 1 << 20
#: The compressions numpy writes (``np.savez``, ``np.savez_compressed``): nothing else is decompressed.
COMPRESSIONS = {zipfile.ZIP_STORED: "stored", zipfile.ZIP_DEFLATED: "deflated"}
_NPY_MAGIC = b"\x93NUMPY"


class ArchiveDamaged(ValueError):
    """Not what a NumPy archive holds, or cut short: the message says what, in one line."""


class ArchiveTooLarge(ValueError):
    """A member (or the archive's directory) larger than its bound: the message names both numbers."""


@dataclass(frozen=True)
class ArrayHeader:
    """What a member's ``.npy`` header says it holds."""

    name: str
    dtype: np.dtype
    shape: tuple[int, ...]
    fortran_order: bool
    #: Bytes of the member before its data (magic, version, length and the header text).
    data_offset: int

    @property
    def nbytes(self) -> int:
        """Bytes of data the header announces (Python ints: no overflow however large the shape)."""
        return math.prod(self.shape) * self.dtype.itemsize


class Archive:
    """The arrays of an ``.npz`` in ``handle`` (a seekable binary file), each read only when asked.

    Opening it checks the archive's directory (:data:`MAX_MEMBERS` members in at most
    :data:`MAX_DIRECTORY_BYTES`), each member's compression and that none is encrypted."""

    def __init__(self, handle: BinaryIO) -> None:
        _check_directory(handle)
        self._zip = zipfile.ZipFile(handle)
        for info in self._zip.infolist():
            if info.flag_bits & 0x1:
                raise ArchiveDamaged(f"{info.filename!r} is encrypted")
            if info.compress_type not in COMPRESSIONS:
                raise ArchiveDamaged(f"{info.filename!r} is compressed in a way numpy never writes "
                                     f"(zip method {info.compress_type}; numpy stores or deflates)")

    def __enter__(self) -> "Archive":
        return self

    def __exit__(self, *exc: object) -> None:
        self._zip.close()

    @property
    def members(self) -> list[str]:
        """Every member's file name, as the directory lists them (a name may be listed twice)."""
        return [info.filename for info in self._zip.infolist()]

    @property
    def arrays(self) -> list[str]:
        """The arrays' names, as ``np.load(...).files`` gives them (``.npy`` dropped)."""
        return [name[:-4] if name.endswith(".npy") else name for name in self.members]

    def header(self, name: str) -> ArrayHeader:
        """What array ``name`` holds, from its ``.npy`` header alone (a few hundred bytes decompressed)."""
        with self._zip.open(_member(name)) as stream:
            return _read_header(stream, name)

    def read(self, name: str, most_bytes: int) -> np.ndarray:
        """Array ``name``, refused before it is allocated if it holds more than ``most_bytes``."""
        info = self._zip.getinfo(_member(name))
        with self._zip.open(info) as stream:
            header = _read_header(stream, name)
            if header.nbytes > most_bytes:
                raise ArchiveTooLarge(f"its {name!r} array unpacks to {header.nbytes:,} bytes; at most {most_bytes:,}")
            if info.file_size != header.data_offset + header.nbytes:
                raise ArchiveDamaged(f"its {name!r} array is {info.file_size:,} bytes in the archive's directory "
                                     f"and {header.data_offset + header.nbytes:,} by its own header")
            data = _read_exactly(stream, header.nbytes, name)
        flat = data.view(header.dtype)
        if header.fortran_order:
            return flat.reshape(header.shape[::-1]).transpose()
        return flat.reshape(header.shape)


def _member(name: str) -> str:
    return f"{name}.npy"


def _check_directory(handle: BinaryIO) -> None:
    """Refuse an archive whose directory lists more members, or takes more bytes, than a few arrays
    need, before zipfile builds an object for every member it lists. The end record is found by
    zipfile's own function, so what is checked is what zipfile will read (a zip64 end record
    included)."""
    end = zipfile._EndRecData(handle)  # noqa: SLF001 - the one reader of the end record zipfile itself uses
    if end is None:
        raise zipfile.BadZipFile("File is not a zip file")
    members, size = end[zipfile._ECD_ENTRIES_TOTAL], end[zipfile._ECD_SIZE]  # noqa: SLF001
    if members > MAX_MEMBERS or size > MAX_DIRECTORY_BYTES:
        raise ArchiveTooLarge(f"its archive lists {members:,} members in a directory of {size:,} bytes; "
                              f"at most {MAX_MEMBERS} members in {MAX_DIRECTORY_BYTES:,} bytes")
    handle.seek(0)


def _read_header(stream: BinaryIO, name: str) -> ArrayHeader:
    """The ``.npy`` header at the start of ``stream``: at most :data:`MAX_NPY_HEADER` bytes read, and a
    dtype that would need a pickle (or is not a plain array of numbers or text) refused."""
    start = stream.read(8)
    if len(start) < 8 or not start.startswith(_NPY_MAGIC):
        raise ArchiveDamaged(f"its {name!r} member is not a NumPy array (.npy)")
    version = (start[6], start[7])
    if version not in ((1, 0), (2, 0)):
        raise ArchiveDamaged(f"its {name!r} array is .npy version {version[0]}.{version[1]}, which numpy writes "
                             "only for named fields")
    length_format = "<H" if version == (1, 0) else "<I"
    length_bytes = stream.read(struct.calcsize(length_format))
    if len(length_bytes) < struct.calcsize(length_format):
        raise ArchiveDamaged(f"its {name!r} array is cut short in its header")
    (length,) = struct.unpack(length_format, length_bytes)
    if length > MAX_NPY_HEADER:
        raise ArchiveTooLarge(f"its {name!r} array's .npy header is {length:,} bytes; at most {MAX_NPY_HEADER:,}")
    text = stream.read(length)
    if len(text) < length:
        raise ArchiveDamaged(f"its {name!r} array is cut short in its header")
    parse = np.lib.format.read_array_header_1_0 if version == (1, 0) else np.lib.format.read_array_header_2_0
    try:
        shape, fortran_order, dtype = parse(io.BytesIO(length_bytes + text), max_header_size=MAX_NPY_HEADER)
    except (ValueError, TypeError, SyntaxError) as exc:
        raise ArchiveDamaged(f"its {name!r} array's .npy header is not one numpy reads "
                             f"({str(exc).splitlines()[0][:120] if str(exc) else type(exc).__name__})") from None
    if dtype.hasobject:
        raise ArchiveDamaged(f"its {name!r} array holds Python objects (a pickle), which this program never reads")
    if dtype.fields is not None or dtype.subdtype is not None or dtype.itemsize == 0:
        raise ArchiveDamaged(f"its {name!r} array is not an array of plain numbers or text ({dtype})")
    if any(size < 0 for size in shape):
        raise ArchiveDamaged(f"its {name!r} array's shape {shape} has a negative size")
    return ArrayHeader(name=name, dtype=dtype, shape=tuple(shape), fortran_order=bool(fortran_order),
                       data_offset=len(start) + len(length_bytes) + length)


def _read_exactly(stream: BinaryIO, nbytes: int, name: str) -> np.ndarray:
    """``nbytes`` from ``stream`` into one array, a chunk at a time, then the member's end: reaching it
    makes zipfile compare the member's CRC, and a byte more means the member holds more than it said."""
    data = np.empty(nbytes, dtype=np.uint8)
    view = memoryview(data)
    filled = 0
    while filled < nbytes:
        chunk = stream.read(min(CHUNK, nbytes - filled))
        if not chunk:
            raise ArchiveDamaged(f"its {name!r} array is cut short: {filled:,} of {nbytes:,} bytes")
        view[filled:filled + len(chunk)] = chunk
        filled += len(chunk)
    if stream.read(1):
        raise ArchiveDamaged(f"its {name!r} array holds more bytes than its header says")
    return data
