"""The platforms an FMU carries a binary for, and the compiler that builds each.

A platform (:class:`Platform`, :data:`PLATFORMS`: ``linux64``, ``win64``, ``darwin64``, the FMI
2.0 folder names; FMI 3.0 ``x86_64-linux`` …) has its shared-library flags; its compiler is this
machine's for its own platform (``$CC``, else cc, gcc, clang), else ``$CC_<NAME>`` or a cross
compiler found on PATH (MinGW-w64 for Windows, osxcross for macOS)
(:func:`platform_compiler`).  The flags are those of every binary the export ships
(:data:`CFLAGS`) and of the rebuild steps it documents (:func:`compile_line`,
:mod:`feeddrive.fmu.rebuild`).
"""

from __future__ import annotations

import platform
import shutil
import sys
from dataclasses import dataclass

from ..backends.c_cache import (  # noqa: F401 - the host's compiler search, re-exported
    CompilerNotFound,
    find_compiler,
    library_suffix,
)

HEADERS = {2: ("fmi2Functions.h", "fmi2FunctionTypes.h", "fmi2TypesPlatform.h"),
           3: ("fmi3Functions.h", "fmi3FunctionTypes.h", "fmi3PlatformTypes.h")}
#: flags of every binary: C99, optimised, no fused multiply-add (numba rounds each operation)
CFLAGS = ("-std=c99", "-O2", "-ffp-contract=off")


@dataclass(frozen=True)
class Platform:
    """A platform an FMU may carry a binary for.

    Parameters
    ----------
    name : str
        Its ``--platform`` name, the FMI 2.0 folder (``linux64``, ``win64``, ``darwin64``).
    fmi3 : str
        The FMI 3.0 folder (``x86_64-linux`` …).
    system : str
        ``sys.platform`` of a machine that runs it natively.
    suffix : str
        The shared library's extension.
    flags : tuple of str
        Compiler flags beside :data:`CFLAGS`: a shared library exporting only the FMI
        functions (two FMUs in one process never bind each other's model), the C runtime
        linked statically where it would be one more DLL.
    libraries : tuple of str
        Libraries linked after the source.
    cross : tuple of str
        Cross compilers looked for on PATH when this machine is not one (Debian's
        ``mingw-w64``; osxcross for macOS).
    """

    name: str
    fmi3: str
    system: str
    suffix: str
    flags: tuple[str, ...]
    libraries: tuple[str, ...]
    cross: tuple[str, ...]

    def folder(self, fmi: int) -> str:
        """The ``binaries/`` folder of this platform in an FMI ``fmi`` FMU.

        Parameters
        ----------
        fmi : int
            FMI version, 2 or 3.

        Returns
        -------
        str
            E.g. ``"win64"`` (FMI 2) or ``"x86_64-windows"`` (FMI 3).
        """
        return self.name if fmi == 2 else self.fmi3

    @property
    def env(self) -> str:
        """The environment variable naming this platform's compiler (``CC_WIN64``)."""
        return f"CC_{self.name.upper()}"


PLATFORMS = {
    "linux64": Platform("linux64", "x86_64-linux", "linux", ".so",
                        ("-fPIC", "-shared", "-fvisibility=hidden"), ("-lm",),
                        ("x86_64-linux-gnu-gcc",)),
    "win64": Platform("win64", "x86_64-windows", "win32", ".dll",
                      ("-shared", "-static-libgcc"), (),
                      ("x86_64-w64-mingw32-gcc", "x86_64-w64-mingw32-clang")),
    "darwin64": Platform("darwin64", "x86_64-darwin", "darwin", ".dylib",
                         ("-fPIC", "-dynamiclib", "-fvisibility=hidden"), (),
                         ("o64-clang", "x86_64-apple-darwin-clang")),
}


def host_platform() -> Platform | None:
    """The platform this machine runs natively, if it is one of :data:`PLATFORMS` (an x86-64
    Linux, Windows or macOS).

    Returns
    -------
    Platform or None
        The platform.
    """
    machine = platform.machine().lower()
    if machine not in ("x86_64", "amd64"):
        return None
    return next((p for p in PLATFORMS.values() if p.system == sys.platform), None)


def platform_folder(fmi: int) -> str:
    """The ``binaries/`` subfolder of this machine (FMI 2 and FMI 3 spell them differently).

    Parameters
    ----------
    fmi : int
        FMI version, 2 or 3.

    Returns
    -------
    str
        E.g. ``"linux64"`` (FMI 2) or ``"x86_64-linux"`` (FMI 3).
    """
    machine = platform.machine().lower()
    arch = {"amd64": "x86_64", "arm64": "aarch64"}.get(machine, machine)
    system = {"linux": "linux", "darwin": "darwin", "win32": "windows"}.get(sys.platform,
                                                                           sys.platform)
    if fmi == 3:
        return f"{arch}-{system}"
    bits = "64" if arch in ("x86_64", "aarch64") else "32"
    return {"linux": "linux", "darwin": "darwin", "windows": "win"}[system] + bits


def platform_compiler(name: str) -> list[str]:
    """The C compiler that builds the binary of the platform ``name``: this machine's
    (:func:`find_compiler`) for its own platform, else ``$CC_<NAME>`` (``CC_WIN64``) or the
    first of the platform's cross compilers on PATH.

    Parameters
    ----------
    name : str
        A platform of :data:`PLATFORMS`.

    Returns
    -------
    list of str
        The command and its fixed arguments.

    Raises
    ------
    CompilerNotFound
        When none is found, with one line naming what was looked for.
    """
    import os
    import shlex

    target = PLATFORMS[name]
    if target == host_platform():
        return find_compiler()
    env = os.environ.get(target.env, "").strip()
    if env:
        cmd = shlex.split(env)
        if shutil.which(cmd[0]) is None:
            raise CompilerNotFound(f"{target.env} = {env!r}: {cmd[0]!r} is not an executable "
                                   "on PATH")
        return cmd
    for cc in target.cross:
        path = shutil.which(cc)
        if path:
            return [path]
    hint = {"win64": "; Debian: apt-get install mingw-w64"}.get(name, "")
    raise CompilerNotFound(
        f"no C compiler for {name} on this machine (looked for ${target.env}, "
        f"{', '.join(target.cross)} on PATH{hint}); build that binary on a {name} machine "
        "from the FMU's sources (documentation/index.html)")


def compile_line(target: str, identifier: str, cc: str = "gcc") -> str:
    """The command line that builds the platform's binary from ``sources/`` (the flags
    :func:`compile_library` uses), for the FMU's documentation.

    Parameters
    ----------
    target : str
        A platform of :data:`PLATFORMS`.
    identifier : str
        The model identifier.
    cc : str, default "gcc"
        The compiler's name in the line.

    Returns
    -------
    str
        E.g. ``"gcc -std=c99 -O2 -ffp-contract=off -fPIC -shared -fvisibility=hidden -I. -o
        feeddrive_cdfs.so fmu.c -lm"``.
    """
    plat = PLATFORMS[target]
    return " ".join([cc, *CFLAGS, *plat.flags, "-I.", "-o", f"{identifier}{plat.suffix}",
                     "fmu.c", *plat.libraries])
