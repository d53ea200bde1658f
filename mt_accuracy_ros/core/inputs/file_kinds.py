"""What a file is, from its first bytes: the one place that knows file signatures.

A user hands ``check`` a PNG, ``info`` a CSV, ``play`` a zipped bag: each reader asks
:func:`file_kind` before it parses, so the refusal names the file's real kind and
the command that reads it, not a parser's complaint about a byte deep inside.
"""
from __future__ import annotations

#: The bytes an MCAP file starts and (when complete) ends with.
MCAP_MAGIC = b"\x89MCAP0\r\n"
#: Bytes read from a file's start to identify it.
IDENTIFY_BYTES = 4096
#: Byte-order marks and the encoding each declares (UTF-32's first: it begins as UTF-16's).
BYTE_ORDER_MARKS = ((b"\xff\xfe\x00\x00", "utf-32"), (b"\x00\x00\xfe\xff", "utf-32"),
                    (b"\xff\xfe", "utf-16"), (b"\xfe\xff", "utf-16"),
                    (b"\xef\xbb\xbf", "utf-8-sig"))
#: Signatures of the files most often given by mistake for a bag or a CSV, and what each is.
FILE_SIGNATURES = (
    (MCAP_MAGIC, "an MCAP bag"),
    (b"\x89PNG\r\n\x1a\n", "a PNG image"), (b"\xff\xd8\xff", "a JPEG image"),
    (b"GIF8", "a GIF image"), (b"%PDF", "a PDF document"),
    (b"PK\x03\x04", "a ZIP archive (a spreadsheet .xlsx or a zipped bag: export it as CSV "
     "or unzip it)"),
    (b"\xd0\xcf\x11\xe0", "an old Excel .xls workbook (export it as CSV)"),
    (b"\x1f\x8b", "a gzip archive (unpack it first)"),
    (b"(\xb5/\xfd", "a zstd-compressed file (decompress it first)"),
    (b"BZh", "a bzip2 archive (unpack it first)"),
    (b"SQLite format 3\x00", "a rosbag2 SQLite (.db3) bag (this package reads MCAP bags: "
     "`ros2 bag convert` it to MCAP)"),
    (b"\x7fELF", "a program (ELF executable)"))
#: Share of a text file's first bytes that are printable (or whitespace, or non-ASCII).
TEXT_SHARE = 0.95


def bom_encoding(data: bytes) -> str:
    """The encoding a byte-order mark at the start of ``data`` declares ("" without one).

    Parameters
    ----------
    data : bytes
        A file's first bytes.

    Returns
    -------
    str
        A codec name (e.g. ``utf-8-sig``, ``utf-16``), or "".
    """
    for mark, encoding in BYTE_ORDER_MARKS:
        if data.startswith(mark):
            return encoding
    return ""


def signature_kind(head: bytes) -> str:
    """What the signature at the start of ``head`` says the file is ("" for none known).

    Parameters
    ----------
    head : bytes
        A file's first bytes.

    Returns
    -------
    str
        What the file is, in words with the mend (e.g. "a gzip archive (unpack it
        first)"), or "".
    """
    for signature, kind in FILE_SIGNATURES:
        if head.startswith(signature):
            return kind
    return ""


def looks_like_text(head: bytes) -> bool:
    """Whether a file's first bytes are text (a CSV, a YAML): a byte-order mark, or no NUL
    byte and (almost) only printable characters, whitespace or non-ASCII letters.

    Parameters
    ----------
    head : bytes
        A file's first bytes.

    Returns
    -------
    bool
        True for text (at least :data:`TEXT_SHARE` of the bytes printable).
    """
    if bom_encoding(head):
        return True
    if not head or b"\x00" in head:
        return False
    printable = sum(32 <= b < 127 or b in b"\t\r\n" or b >= 128 for b in head)
    return printable >= TEXT_SHARE * len(head)


def read_head(path) -> bytes:
    """The first :data:`IDENTIFY_BYTES` bytes of ``path`` (``OSError`` as ``open``).

    Parameters
    ----------
    path : str or os.PathLike
        The file.

    Returns
    -------
    bytes
        Up to :data:`IDENTIFY_BYTES` bytes.

    Raises
    ------
    OSError
        As ``open`` raises it (the caller words it).
    """
    with open(path, "rb") as stream:
        return stream.read(IDENTIFY_BYTES)
