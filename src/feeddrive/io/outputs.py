"""Where results may be written: checked before any work starts.

Rules (docs/outputs.md):

* an output is a file name, never a folder (``reproduce --out`` is the one folder output);
* its folder must exist: a missing folder is refused with its name, not created silently
  (``reproduce --out DIR`` creates DIR itself, but not DIR's parent);
* an output never replaces an input of the same command (measured data, parameter file,
  fragment): that is refused even with ``force``;
* an existing output file is replaced only with ``force`` (``--force`` on the CLI);
* the destination must be writable: probed by opening it (an existing file for update
  without truncating it) and by creating and removing the temporary name it is written under
  (:func:`atomic_path`), so a read-only folder, a read-only mount, a name under a file or a
  name too long for the file system is refused before a simulation or fit runs;
* its format (the extension) is checked with the rest, before any work, where the option
  takes a fixed set of formats (``--plot``: :data:`PLOT_FORMATS`);
* nothing partial is ever left under an output's name: every writer writes through
  :func:`atomic_path`, to a temporary name in the same folder (``.NAME.XXXXXXXX.partial.EXT``),
  flushed to disk and renamed over the final name only once complete, so a full disk, an
  error or a kill mid-write leaves the old file (or none), never a truncated one.

Errors are :class:`OutputError` (a ``ValueError``) naming the option and the path.
"""

from __future__ import annotations

import contextlib
import os
import secrets
from collections.abc import Iterable, Iterator
from pathlib import Path
from typing import Any

__all__ = ["PARQUET_HINT", "PLOT_FORMATS", "RESULT_FORMATS", "SWEEP_EXPORT_FORMATS",
           "OutputError", "atomic_path", "check_output_dir", "check_output_file", "cut",
           "is_same_file", "save_figure", "shown", "write_bytes"]

#: the figure formats every ``--plot`` option takes (matplotlib writes each)
PLOT_FORMATS = (".png", ".pdf", ".svg")
#: longest user text echoed in a one-line message [characters]; longer text is cut
MAX_SHOWN = 200
#: the formats a run's samples are written in (``simulate --output``, ``Result.save``)
RESULT_FORMATS = (".csv", ".parquet", ".nc", ".mat")
#: the formats a sweep is exported in (``sweep``/``map --output``)
SWEEP_EXPORT_FORMATS = (".csv", ".parquet", ".nc")
#: how to get Parquet support (pyarrow is an optional dependency: docs/outputs.md)
PARQUET_HINT = "Parquet output needs pyarrow: pip install 'feeddrive[parquet]'"


class OutputError(ValueError):
    """An output destination was refused; the message names the option and the path."""


def shown(path: str | os.PathLike[str], limit: int | None = MAX_SHOWN) -> str:
    """A path (or any user text) as printed in a one-line message.

    Control characters are escaped (``\\n``, ``\\x1b``) and the text is cut to ``limit``
    characters (:func:`cut`).

    Parameters
    ----------
    path : str or os.PathLike
        The text.
    limit : int or None, default MAX_SHOWN
        Most characters shown; None for no limit.

    Returns
    -------
    str
        The printable text, saying its length when cut.
    """
    text = os.fspath(path)
    length = len(text)
    if limit is not None and length > limit:
        text = text[:limit]  # escape no more than can be shown
    if not text.isprintable():
        text = text.encode("unicode_escape").decode("ascii")
    if limit is not None and (length > limit or len(text) > limit):
        return f"{text[:limit]}… ({length} characters)"
    return text


def cut(text: str, limit: int | None = MAX_SHOWN) -> str:
    """Text cut to about ``limit`` characters, saying how long it was.

    Parameters
    ----------
    text : str
        The text.
    limit : int or None, default MAX_SHOWN
        Most characters kept; None for no limit.

    Returns
    -------
    str
        ``text``, or its start followed by ``… (N characters)``.
    """
    if limit is None or len(text) <= limit:
        return text
    return f"{text[:limit]}… ({len(text)} characters)"


def _partial(p: Path) -> Path:
    """A temporary name for ``p`` in its folder, as :func:`atomic_path` writes under."""
    return p.with_name(f".{p.stem}.{secrets.token_hex(4)}.partial{p.suffix}")


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike[str]) -> Iterator[Path]:
    """A temporary name to write ``path`` under, renamed over it when the block ends.

    The package's one atomic-write helper.  The temporary file is created in the same folder (a
    rename within one file system is atomic), with the permissions a new file gets (the umask),
    named ``.STEM.XXXXXXXX.partial.EXT`` so that a writer choosing its format by the extension
    (matplotlib) still does; it is flushed to disk (``fsync``) before the rename, and removed
    when the block raises.

    Parameters
    ----------
    path : str or os.PathLike
        The file to write.

    Yields
    ------
    Path
        The temporary name to write to.
    """
    p = Path(path)
    # the folder must exist, for every writer (the API's too: `save(params, "new/p.toml")`
    # failed naming the hidden temporary file, and `Result.save` created the folder, against
    # docs/outputs.md: an outside check, 2026-12-07)
    _check_folder("path", p, p.parent if str(p.parent) else Path("."))
    while True:
        tmp = _partial(p)
        try:
            os.close(os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666))
            break
        except FileExistsError:
            continue
    try:
        yield tmp
        fd = os.open(tmp, os.O_RDONLY)
        try:
            os.fsync(fd)
        finally:
            os.close(fd)
        os.replace(tmp, p)
    except BaseException:
        with contextlib.suppress(OSError):
            os.unlink(tmp)
        raise


def _write_fd(fd: int, data: memoryview) -> int:
    return os.write(fd, data)


def write_bytes(path: str | os.PathLike[str], data: bytes | memoryview) -> None:
    """Write ``data`` to ``path`` with plain file I/O, 1 MiB at a time.

    For a file a library builds in memory (NetCDF4): a failed write (a full disk) is then an
    ordinary ``OSError`` here, not the library's failure deep inside its own I/O.  The
    caller makes it atomic (:func:`atomic_path`).

    Parameters
    ----------
    path : str or os.PathLike
        The file, created or truncated.
    data : bytes or memoryview
        Its contents.

    Raises
    ------
    OSError
        When a write fails (``ENOSPC``, ``EFBIG``), without the file name: the caller knows
        which output it is.
    """
    view = memoryview(data).cast("B")
    fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o666)
    try:
        while view.nbytes:
            view = view[_write_fd(fd, view[:1 << 20]):]
    finally:
        os.close(fd)


def save_figure(fig: Any, path: str | os.PathLike[str], *, dpi: int,
                tight: bool = False) -> Path:
    """Write a matplotlib figure atomically (:func:`atomic_path`), the format following the
    extension.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
        The figure.
    path : str or os.PathLike
        The image file.
    dpi : int
        Resolution [dots per inch].
    tight : bool, default False
        No margin cut off (``bbox_inches="tight"``).

    Returns
    -------
    Path
        The file written.
    """
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=dpi, **({"bbox_inches": "tight"} if tight else {}))
    return Path(path)

def is_same_file(a: str | os.PathLike[str], b: str | os.PathLike[str]) -> bool:
    """Whether two names are one file: the same file now, or the same resolved path.

    Parameters
    ----------
    a, b : str or os.PathLike
        The names.

    Returns
    -------
    bool
        True when writing ``a`` would replace ``b``.
    """
    pa, pb = Path(a), Path(b)
    try:
        if pa.exists() and pb.exists() and os.path.samefile(pa, pb):
            return True
    except OSError:
        pass
    return pa.resolve() == pb.resolve()


def _check_folder(option: str, p: Path, folder: Path) -> None:
    """``folder`` (the output's parent) must exist and be a folder."""
    if folder.is_dir():
        return
    # walk up to the first existing ancestor to say what is wrong
    probe = folder
    while not probe.exists() and probe != probe.parent:
        probe = probe.parent
    if probe.exists() and not probe.is_dir():
        raise OutputError(f"{option} {shown(p)}: {shown(probe)} is a file, not a folder")
    raise OutputError(f"{option} {shown(p)}: folder {shown(folder)} does not exist; create it "
                      "first")


def _probe_writable(option: str, p: Path, probe: Path | None = None) -> None:
    """Open ``p`` for update (it exists), and create and remove ``probe`` (default: the
    temporary name :func:`atomic_path` would write ``p`` under, 18 characters longer, so a
    name the file system cannot hold is refused now, not after the work)."""
    try:
        if probe is None and p.exists():
            with open(p, "r+b"):
                pass
        target = probe or _partial(p)
        fd = os.open(target, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o644)
        os.close(fd)
        os.unlink(target)
    except OSError as err:
        raise OutputError(f"{option} {shown(p)}: cannot write here "
                          f"({err.strerror or err})") from None


def check_output_file(path: str | os.PathLike[str], *, option: str,
                      inputs: Iterable[str | os.PathLike[str] | None] = (),
                      force: bool = False, formats: Iterable[str] | None = None) -> Path:
    """Refuse a path as an output file unless it can be written, before any work starts.

    See the module's rules: not empty, not a folder, its folder exists and is writable, not one
    of the command's inputs, not an existing file unless ``force``, an accepted extension.

    Parameters
    ----------
    path : str or os.PathLike
        The output file.
    option : str
        The CLI option (``--out``), named in messages.
    inputs : iterable of (str or os.PathLike or None), optional
        The files the command reads, which an output may never replace.
    force : bool, default False
        Whether an existing file may be replaced.
    formats : iterable of str, optional
        The extensions the option takes; any when None.

    Returns
    -------
    Path
        The path.

    Raises
    ------
    OutputError
        One line naming the option, the path and the problem.
    """
    try:
        return _check_output_file(os.fspath(path), option=option, inputs=inputs, force=force,
                                  formats=formats)
    except OSError as err:  # a name the file system refuses to look up (too long, a loop)
        raise OutputError(f"{option} {shown(path)}: {err.strerror or err}") from None


def _check_output_file(text: str, *, option: str,
                       inputs: Iterable[str | os.PathLike[str] | None], force: bool,
                       formats: Iterable[str] | None) -> Path:
    if not text.strip():
        raise OutputError(f"{option} {text!r}: empty file name")
    p = Path(text)
    if p.is_dir():
        raise OutputError(f"{option} {shown(p)}: is a folder; expected a file name")
    _check_folder(option, p, p.parent)
    for inp in inputs:
        if inp is None:
            continue
        if is_same_file(p, inp):
            raise OutputError(f"{option} {shown(p)}: is an input of this command; refusing to "
                              "overwrite it")
    if formats is not None:
        allowed = tuple(formats)
        if p.suffix.lower() not in allowed:
            names = allowed[0] if len(allowed) == 1 else \
                f"{', '.join(allowed[:-1])} or {allowed[-1]}"
            raise OutputError(f"{option} {shown(p)}: expected a {names} file name")
    if p.suffix.lower() == ".parquet":
        import importlib.util

        if importlib.util.find_spec("pyarrow") is None:
            raise OutputError(f"{option} {shown(p)}: {PARQUET_HINT}")
    if p.exists() and not force:
        raise OutputError(f"{option} {shown(p)}: exists; pass --force to replace it")
    _probe_writable(option, p)
    return p


def check_output_dir(path: str | os.PathLike[str], *, option: str) -> Path:
    """Refuse a path as an output folder unless it is a writable folder or a new name in one.

    The command writes only its own file names into it, so an input kept there is never
    replaced.

    Parameters
    ----------
    path : str or os.PathLike
        The output folder.
    option : str
        The CLI option, named in messages.

    Returns
    -------
    Path
        The path.

    Raises
    ------
    OutputError
        For an empty name, a file, a missing parent or a folder that cannot be written.
    """
    try:
        return _check_output_dir(os.fspath(path), option=option)
    except OSError as err:  # a name the file system refuses to look up (too long, a loop)
        raise OutputError(f"{option} {shown(path)}: {err.strerror or err}") from None


def _check_output_dir(text: str, *, option: str) -> Path:
    if not text.strip():
        raise OutputError(f"{option} {text!r}: empty folder name")
    p = Path(text)
    if p.exists() and not p.is_dir():
        raise OutputError(f"{option} {shown(p)}: is a file; expected a folder")
    if not p.exists():
        _check_folder(option, p, p.parent)
        try:  # a name the file system cannot hold is refused now (the folder is made later)
            os.mkdir(p)
            os.rmdir(p)
        except OSError as err:
            raise OutputError(f"{option} {shown(p)}: cannot write here "
                              f"({err.strerror or err})") from None
    folder = p if p.exists() else p.parent
    _probe_writable(option, p, folder / f".feeddrive-write-probe-{os.getpid()}")
    return p
