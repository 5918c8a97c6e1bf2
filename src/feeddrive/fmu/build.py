"""Generate the FMU's C source, compile it with the machine's C compiler, zip the FMU.

One translation unit ``fmu.c``: the model (:func:`feeddrive.backends.c_backend.c_model_source`),
the integrator translated from the driver's ``COMM`` specialisation
(:func:`feeddrive.fmu.solver.advance_function`), the variable tables
(:mod:`feeddrive.fmu.description`) and the FMI functions (``wrapper.c``).  It needs only the C
standard library and libm; the FMU carries it (with the FMI headers) under
``sources/`` so it can be rebuilt for another platform (docs/fmu.md).
"""

from __future__ import annotations

import shutil
import tempfile
import zipfile
from importlib import resources
from pathlib import Path

from ..backends.c_cache import CompileError, compile_c  # noqa: F401 (CompileError: its error)
from ..solvers import schedule, steps
from . import solver
from .description import Provenance, Variable, c_tables, model_description
from .model import FmuModel
from .platforms import (  # noqa: F401 - the compiler search, re-exported for its callers
    CFLAGS,
    HEADERS,
    PLATFORMS,
    CompilerNotFound,
    Platform,
    compile_line,
    find_compiler,
    host_platform,
    library_suffix,
    platform_compiler,
    platform_folder,
)


def solver_c() -> str:
    """C text of the FMU's integrator (``fd_advance``), translated from the same Python the
    numba build compiles, with the model's ``fd_rhs`` / ``fd_sample_update`` as its ``rhs`` /
    ``sample_update`` and the DOPRI5 step and error norm of :mod:`feeddrive.solvers.steps`
    translated with it (the driver of :mod:`feeddrive.solvers.driver` specialised ``COMM``,
    :func:`feeddrive.fmu.solver.advance_function`).

    Returns
    -------
    str
        The C text.
    """
    from ..backends.c_backend import (
        RHS,
        SAMPLE_UPDATE,
        SOLVER_SHAPES,
        SOLVER_TYPES,
        translate_kernels,
    )

    shapes = dict(SOLVER_SHAPES)
    shapes.update({"held": ("FD_N_HELD",), "held_prev": ("FD_N_HELD",), "aux": ("FD_N_AUX",),
                   "f_new": ("FD_N_STATE",), "memory": ("FD_MEMORY_SIZE",)})
    return translate_kernels(
        [solver.advance_function()], dict(solver.CONSTANTS), param_types=SOLVER_TYPES,
        bindings={"rhs": RHS, "sample_update": SAMPLE_UPDATE,
                  "_dp5_step": steps.function("_dp5_step"),
                  "_dp5_error": steps.function("_dp5_error"),
                  "_error_norm": steps.error_norm_template,
                  "_pi_factor": steps.pi_factor_template,
                  "_reject_factor": steps.reject_factor_template},
        shapes=shapes, names={"advance": "fd_advance"})


#: activity of the generated rhs's parameters in its tangents (feeddrive.backends.tangent):
#: the states vary, and the reference block of T (the inputs); the held controller values and
#: the parameters are constants of a Jacobian — but for the load force, a slot of P, in the
#: second tangent
TANGENT_KINDS = {"t": "c", "y": "a", "held": "ca", "P": "ca", "T": "a", "dy": "a", "aux": "a"}


def tangent_c(fm: FmuModel) -> str:
    """C text of the model's tangents (model exchange): ``fd_rhs_tangent(t, y, held, P, T,
    dy, aux, y_d, T_d, dy_d, aux_d)`` — the derivatives' and signals' directional derivatives
    for a seed of the states and of the reference block of T — and ``fd_rhs_tangent_all``,
    which takes a seed of P too (``…, y_d, P_d, T_d, dy_d, aux_d``: the load-force input).
    Both generated from the model's own kernels (:func:`feeddrive.backends.tangent.tangent`)
    and translated to C with them.

    Parameters
    ----------
    fm : FmuModel
        The assembled model.

    Returns
    -------
    str
        The C text.
    """
    from ..backends.c_translate import translate_kernels
    from ..backends.tangent import tangent

    rhs = fm.model.module.rhs.py_func
    states_and_inputs, _ = tangent(rhs, TANGENT_KINDS)
    with_parameters, _ = tangent(rhs, {**TANGENT_KINDS, "P": "a"})
    return translate_kernels([states_and_inputs, with_parameters],
                             names={states_and_inputs.__name__: "fd_rhs_tangent",
                                    with_parameters.__name__: "fd_rhs_tangent_all"})


def fmu_source(fm: FmuModel, vs: list[Variable], *, fmi: int, kind: str, token: str) -> str:
    """The whole ``fmu.c``.

    Parameters
    ----------
    fm : FmuModel
        The assembled model and where its inputs live.
    vs : list of Variable
        The FMU's variables (:func:`feeddrive.fmu.description.variables`).
    fmi : int
        FMI version, 2 or 3.
    kind : str
        ``"cs"`` or ``"me"``.
    token : str
        The instantiation token (GUID) the description declares.

    Returns
    -------
    str
        The C source.
    """
    from ..backends.c_backend import c_model_source
    from ..backends.c_translate import _mangle

    wrapper = resources.files(__package__).joinpath("wrapper.c").read_text(encoding="utf-8")
    memory = "\n".join(f"#define FD_{name} {value}" for name, value in solver.CONSTANTS.items()
                       if name.startswith("MEM_"))
    parts = [
        f"/* feeddrive FMU of the {fm.drive} drive (FMI {fmi}.0, "
        f"{'model exchange' if kind == 'me' else 'co-simulation'}).  Generated by "
        "feeddrive.fmu: do not edit, export again. */",
        "/* ---- the model (feeddrive.backends.c_backend) */",
        c_model_source(fm.model),
        "/* ---- the integrator (feeddrive.solvers.driver, specialised COMM, translated) */",
        f"#define FD_MEMORY_SIZE {solver.MEMORY_SIZE}",
        memory,
        solver_c(),
        "#define FD_ADVANCE fd_advance",
        # the schedule's kernels, translated with the integrator (it calls them)
        f"#define FD_DUE {_mangle(schedule.due.py_func)}",
        f"#define FD_NEXT_INSTANT {_mangle(schedule.next_instant.py_func)}",
        *(["/* ---- the model's tangent (feeddrive.backends.tangent): directional "
           "derivatives */", tangent_c(fm)] if kind == "me" else []),
        "/* ---- variables and start values (feeddrive.fmu.description) */",
        c_tables(fm, vs, fmi=fmi, kind=kind, token=token),
        "/* ---- the FMI functions */",
        wrapper,
    ]
    return "\n".join(parts)


def compile_library(source: str, fmi: int, folder: Path, identifier: str, *,
                    export_all: bool = False, target: str | None = None) -> Path:
    """Compile ``source`` (with the FMI headers beside it) into ``folder/<identifier><ext>``
    for the platform ``target`` (this machine's by default); ``export_all``: the model's and
    integrator's functions visible too (tests call them).

    Parameters
    ----------
    source : str
        The C source (``fmu.c``).
    fmi : int
        FMI version, 2 or 3 (which headers).
    folder : Path
        Where to write the source and the library.
    identifier : str
        The library's name.
    export_all : bool, default False
        Export every function, not only the FMI ones.
    target : str, optional
        A platform of :data:`PLATFORMS`; None: this machine's, with its compiler.

    Returns
    -------
    Path
        The library.

    Raises
    ------
    CompilerNotFound
        Without a C compiler for the platform.
    CompileError
        When the compiler fails (a RuntimeError: one line with its first error line).
    """
    plat = PLATFORMS[target] if target else host_platform() or PLATFORMS["linux64"]
    cc = platform_compiler(target) if target else find_compiler()
    include = resources.files(__package__).joinpath("include")
    files = {"fmu.c": source, **{name: include.joinpath(name).read_text(encoding="utf-8")
                                 for name in HEADERS[fmi]}}
    suffix = plat.suffix if target else library_suffix()
    flags = [f for f in (*CFLAGS, *plat.flags)
             if not (export_all and f.startswith("-fvisibility"))]
    return compile_c(files, folder, f"{identifier}{suffix}", cc, [*flags, f"-I{folder}"],
                     plat.libraries)


def build_description(identifier: str) -> str:
    """The ``sources/buildDescription.xml`` of an FMI 3 FMU: one C99 source, ``fmu.c``.

    Parameters
    ----------
    identifier : str
        The model identifier.

    Returns
    -------
    str
        The XML text.
    """
    return ('<?xml version="1.0" encoding="UTF-8"?>\n'
            '<fmiBuildDescription fmiVersion="3.0">\n'
            f'  <BuildConfiguration modelIdentifier="{identifier}">\n'
            '    <SourceFileSet language="C99">\n'
            '      <SourceFile name="fmu.c"/>\n'
            '    </SourceFileSet>\n'
            '  </BuildConfiguration>\n'
            '</fmiBuildDescription>\n')


#: the FMU's licence folder (FMI 3.0 Sect. 2.5: ``documentation/licenses``, entry point
#: ``license.txt``; the same place in an FMI 2.0 FMU)
LICENSES = "documentation/licenses"
FMI_HEADERS_LICENSE = "FMI-headers-BSD-2-Clause.txt"
PACKAGE_LICENSE = "feeddrive-MIT.txt"


def package_license() -> str:
    """The package's own licence text (its distribution's ``licenses/LICENSE``; the source
    tree's ``LICENSE`` when run from a checkout).

    Returns
    -------
    str
        The text.
    """
    from importlib import metadata

    try:
        text = metadata.distribution("feeddrive").read_text("licenses/LICENSE")
    except metadata.PackageNotFoundError:  # pragma: no cover - always installed
        text = None
    if text is None:  # pragma: no cover - an install without PEP 639 licence files
        text = (Path(__file__).resolve().parents[3] / "LICENSE").read_text(encoding="utf-8")
    return text


def provenance() -> Provenance:
    """Author, version, copyright and licence of an FMU written now (the package's metadata,
    its licence and that of the FMI headers the FMU carries).

    Returns
    -------
    Provenance
        The attributes of ``modelDescription.xml``.
    """
    import datetime
    import os
    from importlib import metadata

    from .. import __version__

    try:
        author = metadata.metadata("feeddrive")["Author"] or "the feeddrive maintainers"
    except metadata.PackageNotFoundError:  # pragma: no cover - always installed
        author = "the feeddrive maintainers"
    own = next(line.strip() for line in package_license().splitlines()
               if line.startswith("Copyright"))
    epoch = os.environ.get("SOURCE_DATE_EPOCH")
    now = (datetime.datetime.fromtimestamp(int(epoch), datetime.UTC) if epoch
           else datetime.datetime.now(datetime.UTC))
    return Provenance(
        author=author, version=__version__,
        copyright=(f"{own} (model and integrator code); FMI headers: Copyright (C) 2008-2011 "
                   "MODELISAR consortium, 2012-2023 Modelica Association Project \"FMI\""),
        license=(f"MIT (feeddrive, {LICENSES}/{PACKAGE_LICENSE}) AND BSD-2-Clause (the FMI "
                 f"headers in sources/, {LICENSES}/{FMI_HEADERS_LICENSE})"),
        generation_tool=f"feeddrive {__version__}",
        generation_time=now.strftime("%Y-%m-%dT%H:%M:%SZ"))


def license_files() -> dict[str, str]:
    """The files of the FMU's licence folder: the entry point ``license.txt``, the package's
    MIT licence and the FMI headers' BSD-2-Clause licence.

    Returns
    -------
    dict of str to str
        Path in the FMU → text.
    """
    fmi = resources.files(__package__).joinpath("include", "LICENSE.txt").read_text(
        encoding="utf-8")
    entry = (
        "Licences of this FMU\n====================\n\n"
        "The model, its integrator and the FMI functions (sources/fmu.c and the binaries\n"
        f"built from it) were generated by feeddrive: MIT licence, {PACKAGE_LICENSE}.\n\n"
        "The FMI headers in sources/ (fmi2*.h or fmi3*.h) are the Functional Mock-up\n"
        "Interface standard's: 2-Clause BSD licence (SPDX BSD-2-Clause),\n"
        f"{FMI_HEADERS_LICENSE}.\n")
    return {f"{LICENSES}/license.txt": entry, f"{LICENSES}/{PACKAGE_LICENSE}": package_license(),
            f"{LICENSES}/{FMI_HEADERS_LICENSE}": fmi}


def package(out: Path, fm: FmuModel, vs: list[Variable], *, fmi: int, kind: str,
            identifier: str, token: str, description: str, provenance: Provenance,
            platforms: tuple[str, ...] | None = None) -> Path:
    """Write the FMU ``out`` (a zip): modelDescription.xml, a binary per platform, the
    sources with their ``CMakeLists.txt``, ``documentation/index.html`` (how to rebuild) and
    the licences.

    Parameters
    ----------
    out : Path
        The ``.fmu`` file, written atomically.
    fm : FmuModel
        The assembled model and where its inputs live.
    vs : list of Variable
        The FMU's variables (:func:`feeddrive.fmu.description.variables`).
    fmi : int
        FMI version, 2 or 3.
    kind : str
        ``"cs"`` or ``"me"``.
    identifier : str
        The model identifier.
    token : str
        The instantiation token (GUID).
    description : str
        The model's description text.
    provenance : Provenance
        Author, version, copyright, licence, generation tool and time.
    platforms : tuple of str, optional
        Platforms of :data:`PLATFORMS` to build a binary for, each with its compiler
        (:func:`platform_compiler`); None: this machine's, with its compiler.

    Returns
    -------
    Path
        ``out``.
    """
    from .rebuild import cmake_lists, index_html

    source = fmu_source(fm, vs, fmi=fmi, kind=kind, token=token)
    xml = model_description(fm, vs, fmi=fmi, kind=kind, identifier=identifier, token=token,
                            description=description, provenance=provenance)
    with tempfile.TemporaryDirectory(prefix="feeddrive-fmu-") as tmp:
        libs: list[tuple[str, Path]] = []
        if platforms is None:
            libs.append((platform_folder(fmi),
                         compile_library(source, fmi, Path(tmp) / "host", identifier)))
        else:
            for name in platforms:
                lib = compile_library(source, fmi, Path(tmp) / name, identifier, target=name)
                libs.append((PLATFORMS[name].folder(fmi), lib))
        from ..io.outputs import atomic_path

        with atomic_path(out) as partial, \
                zipfile.ZipFile(partial, "w", zipfile.ZIP_DEFLATED) as zf:
            zf.writestr("modelDescription.xml", xml)
            for folder, lib in libs:
                zf.write(lib, f"binaries/{folder}/{lib.name}")
            zf.writestr("sources/fmu.c", source)
            for name in HEADERS[fmi]:
                zf.write(libs[0][1].parent / name, f"sources/{name}")
            zf.writestr("sources/CMakeLists.txt", cmake_lists(identifier, fmi))
            if fmi == 3:
                zf.writestr("sources/buildDescription.xml", build_description(identifier))
            zf.writestr("documentation/index.html", index_html(
                identifier, fmi, kind, description, [f for f, _ in libs], provenance.version))
            for name, text in license_files().items():
                zf.writestr(name, text)
    return out


def which_compiler() -> str:
    """The compiler's path, for messages.

    Returns
    -------
    str
        The path, or the command as given.
    """
    return shutil.which(find_compiler()[0]) or find_compiler()[0]
