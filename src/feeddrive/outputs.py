"""Where results may be written: checked before any work starts.

Rules (docs/outputs.md):

* an output is a file name, never a folder (``reproduce --out`` is the one folder output);
* its folder must exist: a missing folder is refused with its name, not created silently
  (``reproduce --out DIR`` creates DIR itself, but not DIR's parent);
* an output never replaces an input of the same command (measured data, parameter file,
  fragment): that is refused even with ``force``;
* an existing output file is replaced only with ``force`` (``--force`` on the CLI);
* the destination must be writable: probed by opening it (an existing file for update
  without truncating it, a new name by creating and removing it), so a read-only folder, a
  read-only mount or a name under a file is refused before a simulation or fit runs.

Errors are :class:`OutputError` (a ``ValueError``) naming the option and the path.
"""

from __future__ import annotations

import os
from collections.abc import Iterable
from pathlib import Path

__all__ = ["OutputError", "check_output_dir", "check_output_file", "shown"]


class OutputError(ValueError):
    """An output destination was refused; the message names the option and the path."""


def shown(path: str | os.PathLike[str]) -> str:
    """A path as printed in a one-line message: control characters escaped (``\\n``)."""
    text = os.fspath(path)
    if text.isprintable():
        return text
    return text.encode("unicode_escape").decode("ascii")


def _same_file(a: Path, b: Path) -> bool:
    try:
        return a.exists() and b.exists() and os.path.samefile(a, b)
    except OSError:
        return False


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
    """Open ``p`` for update (it exists) or create and remove ``probe`` (default ``p``)."""
    try:
        if probe is None and p.exists():
            with open(p, "r+b"):
                pass
        else:
            target = probe or p
            fd = os.open(target, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o644)
            os.close(fd)
            os.unlink(target)
    except OSError as err:
        raise OutputError(f"{option} {shown(p)}: cannot write here "
                          f"({err.strerror or err})") from None


def check_output_file(path: str | os.PathLike[str], *, option: str,
                      inputs: Iterable[str | os.PathLike[str] | None] = (),
                      force: bool = False) -> Path:
    """Refuse ``path`` as an output file unless it can be written (see the module rules).

    ``option`` names the CLI option (``--out``) in messages; ``inputs`` are the files the
    command reads, which an output may never replace.  Returns the path.
    """
    text = os.fspath(path)
    if not text.strip():
        raise OutputError(f"{option} {text!r}: empty file name")
    p = Path(text)
    if p.is_dir():
        raise OutputError(f"{option} {shown(p)}: is a folder; expected a file name")
    _check_folder(option, p, p.parent)
    for inp in inputs:
        if inp is None:
            continue
        if _same_file(p, Path(inp)) or p.resolve() == Path(inp).resolve():
            raise OutputError(f"{option} {shown(p)}: is an input of this command; refusing to "
                              "overwrite it")
    if p.exists() and not force:
        raise OutputError(f"{option} {shown(p)}: exists; pass --force to replace it")
    _probe_writable(option, p)
    return p


def check_output_dir(path: str | os.PathLike[str], *, option: str) -> Path:
    """Refuse ``path`` as an output folder: it must be a writable folder or a new name in an
    existing, writable folder.  Returns the path.  (The command writes only its own file
    names into it, so an input kept there is never replaced.)"""
    text = os.fspath(path)
    if not text.strip():
        raise OutputError(f"{option} {text!r}: empty folder name")
    p = Path(text)
    if p.exists() and not p.is_dir():
        raise OutputError(f"{option} {shown(p)}: is a file; expected a folder")
    if not p.exists():
        _check_folder(option, p, p.parent)
    folder = p if p.exists() else p.parent
    _probe_writable(option, p, folder / f".feeddrive-write-probe-{os.getpid()}")
    return p
