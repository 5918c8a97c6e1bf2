"""Record the regression corpus of issue 40 (named signals between parts) before the change.

The corpus is generated from the registry, not kept by hand:

* every registered topology (``feeddrive.mechanisms``) with its ``example_preset``, crossed
  with every registered friction law (``feeddrive.friction_laws``) at every friction site of
  that topology (a law with a parameter class of its own takes its site table from the first
  ``examples/*.toml`` that uses it, e.g. ``examples/gms_guide.toml`` for ``gms``);
* every topology crossed with every loop configuration: each non-default value of every
  ``choice`` field of the ``[controller]`` section and of its sub-sections (kv placement,
  gain basis, feedback, nut loop, torque off, compensation mode …), and the sampled loops
  (1 ms / 0.5 ms / 0.125 ms, as ``reference/record_engine_v1.py``);
* every registered preset on its own example topology (disturbances: ripple, lead error …);
* every registered section no preset carries (``model/parts/``), with the values of the first
  ```` ```toml ```` block of ``docs/`` that gives it, on every topology.

For each case: the structure (state, signal and parameter names, the Jacobian pattern, the
clocks), the packed ``P``, the right-hand side (rates and signals) at a random state, and a
short ``dopri5`` run at fixed tolerances, stepping across friction reversals (every state and
signal at 5 instants).  Run with the
tree before the change (commit d4dd4b5)::

    python reference/record_signal_corpus.py tests/data/signal_corpus_d4dd4b5.npz

``tests/validation/test_signal_corpus.py`` rebuilds the same cases with the current tree and
compares: bit for bit, except where an operation order had to move (listed in that test).

Cases a later option or part adds are recorded at that commit into a supplement that holds only
them (``python reference/record_signal_corpus.py SUPPLEMENT.npz BASE.npz …``), listed in the
test beside the base record.
"""

from __future__ import annotations

import dataclasses
import json
import re
import sys
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
DURATION = 0.02  # [s]
OUTPUT_INTERVAL = 0.005  # [s]
TABLE_SPEED = 2e-3  # [m/s]
NUT_SPEED = 16e-3  # [m/s], for the drives that follow a nut reference (DDFS)
SAMPLED = (("controller.position_period", 1e-3), ("controller.velocity_period", 5e-4),
           ("controller.current_period", 1.25e-4))


@dataclasses.dataclass(frozen=True)
class Case:
    """One corpus entry: a parameter set on a topology."""

    name: str
    drive: str
    parameters: Any


def _choices(component: Any, path: str) -> Iterator[tuple[str, str]]:
    """(dotted path, value) of every non-default value of every ``choice`` field, recursively."""
    for f in dataclasses.fields(component):
        value = getattr(component, f.name)
        if dataclasses.is_dataclass(value) and not isinstance(value, type):
            yield from _choices(value, f"{path}.{f.name}")
        for option in f.metadata.get("options", ()):
            if option != value:
                yield f"{path}.{f.name}", option


def _law_examples() -> dict[str, dict[str, Any]]:
    """Law name → the site table of the first example file that uses it."""
    from feeddrive.parameters.toml_io import parse_toml

    found: dict[str, dict[str, Any]] = {}
    for path in sorted((ROOT / "examples").glob("*.toml")):
        data = parse_toml(path.read_text())
        for table in data.get("friction", {}).values():
            if isinstance(table, dict) and "law" in table:
                found.setdefault(table["law"], table)
    return found


def _section_examples() -> dict[str, str]:
    """Section name → the first docs TOML block that gives it as a table."""
    found: dict[str, str] = {}
    for doc in sorted((ROOT / "docs").rglob("*.md")):
        for block in re.findall(r"```toml\n(.*?)```", doc.read_text(encoding="utf-8"), re.S):
            for section in re.findall(r"^\[([a-z_]+)\]", block, re.M):
                found.setdefault(section, block)
    return found


def _toml_table(path: str, table: dict[str, Any]) -> str:
    lines = [f"[{path}]"]
    nested = []
    for key, value in table.items():
        if isinstance(value, dict):
            nested.append((f"{path}.{key}", value))
        else:
            lines.append(f"{key} = {json.dumps(value)}")
    return "\n".join(lines + [_toml_table(p, t) for p, t in nested])


def cases() -> list[Case]:
    """Every case of the corpus, generated from the registry."""
    import feeddrive as fd
    from feeddrive import registry
    from feeddrive.model.mechanisms import mechanism
    from feeddrive.parameters.toml_io import loads

    out: list[Case] = []
    seen_sections: set[str] = set()
    drives = registry.names(registry.MECHANISMS)
    law_tables = _law_examples()
    for drive in drives:
        mech_cls = mechanism(drive)
        base = fd.preset(mech_cls.example_preset)
        seen_sections.update(name for name, _ in base.sections)
        mech = mech_cls(base, drive, 0.4, "locked")
        from feeddrive.model.codegen import Builder

        b = Builder()
        mech.declare(b)
        mech.parameters(b)
        keys = [s.parameters_key for s in mech.sites(b)]
        for law in registry.names(registry.FRICTION_LAWS):
            blocks = [f'extends = "{mech_cls.example_preset}"']
            for key in dict.fromkeys(keys):
                path = key if "." in key else f"friction.{key}"
                table = law_tables.get(law)
                blocks.append(_toml_table(path, table) if table is not None
                              else f'[{path}]\nlaw = "{law}"')
            out.append(Case(f"{drive}/law={law}", drive, loads("\n".join(blocks))))
        for path, value in _choices(base.controller, "controller"):
            out.append(Case(f"{drive}/{path}={value}", drive, base.replace_path(path, value)))
        sampled = base
        for path, value in SAMPLED:
            sampled = sampled.replace_path(path, value)
        out.append(Case(f"{drive}/sampled", drive, sampled))
    for name in registry.names(registry.PRESETS):
        params = fd.preset(name)
        seen_sections.update(n for n, _ in params.sections)
        for drive in drives:
            if mechanism(drive).example_preset == name or (
                    name.startswith("wang2021") and drive in ("cdfs", "ddfs")):
                out.append(Case(f"{drive}/preset={name}", drive, params))
    docs = _section_examples()
    for section in registry.names(registry.SECTIONS):
        if section in seen_sections or section not in docs:
            continue
        table = re.search(rf"^\[{section}\]\n(?:[^\[].*\n?)*", docs[section], re.M)
        assert table is not None
        for drive in drives:
            text = f'extends = "{mechanism(drive).example_preset}"\n{table.group(0)}'
            out.append(Case(f"{drive}/section={section}", drive, loads(text)))
    return out


def record(case: Case) -> dict[str, Any]:
    """The structure and numbers of one case (see the module docstring)."""
    import feeddrive as fd
    from feeddrive.engine.options import LEGACY_TOLERANCES
    from feeddrive.model.reference import ConstantSpeed

    system = fd.DriveSystem(case.parameters, case.drive, 0.4)
    nut = NUT_SPEED if system.topology().follows("nut") else 0.0
    profile = ConstantSpeed(TABLE_SPEED, nut)
    model = system.model(profile)
    rng = np.random.default_rng(40)
    y = rng.normal(size=len(model.state_names)) * np.array(
        [{"position": 1e-6, "angle": 1e-4, "speed": 1e-3, "rotary_speed": 1e-1,
          "current": 1e-1, "current_integral": 1e-4, "velocity_integral": 1e-4,
          "deflection": s, "none": 1e-6}[k]
         for k, s in zip(model.tolerance_kinds, model.tolerance_scales, strict=True)])
    held = rng.normal(size=model.n_held) * 1e-2
    dy = np.zeros(len(model.state_names))
    aux = np.zeros(len(model.aux))
    model.module.compiled("_ev_rates")(1.25e-3, y, held, model.P, model.T, dy, aux)
    # stepping across the friction reversals, as dopri5 did when the corpus was recorded (a
    # tree that has the setting: dopri5 has located them by default since issue 35)
    across = ({"locate_reversals": False}
              if "locate_reversals" in {f.name for f in dataclasses.fields(fd.SolverOptions)}
              else {})
    result = fd.simulate(system, profile, DURATION, options=fd.SolverOptions(
        method="dopri5", output_interval=OUTPUT_INTERVAL, **LEGACY_TOLERANCES, **across))
    names = list(model.state_names) + [a.name for a in model.aux]
    return {
        "structure": {
            "states": list(model.state_names), "aux": [a.name for a in model.aux],
            "parameters": list(model.parameter_names),
            "clocks": [c for c, _ in model.clocks],
            "flows": {w: list(r) for w, r in model.flows},
        },
        "P": model.P, "pattern": np.packbits(model.jacobian_pattern),
        "y": y, "held": held, "dy": dy, "aux": aux,
        "time": result.time,
        "run": np.stack([np.asarray(result[n], dtype=float) for n in names]),
    }


def main(out: str, *base: str) -> None:
    """Record every case into ``out``; with ``base`` records given, only the cases none of them
    holds (a supplement for cases a later option or part adds, recorded at its own commit)."""
    import feeddrive as fd

    known: set[str] = set()
    for path in base:
        known.update(json.loads(str(np.load(path)["structure"])))
    arrays: dict[str, np.ndarray] = {}
    structure: dict[str, Any] = {}
    for case in cases():
        if case.name in known:
            continue
        print(case.name, flush=True)
        try:
            rec = record(case)
        except (fd.ParameterError, ValueError) as exc:  # a refusal is recorded as such
            structure[case.name] = {"error": str(exc)}
            continue
        structure[case.name] = rec.pop("structure")
        for key, value in rec.items():
            arrays[f"{case.name}|{key}"] = np.asarray(value)
    arrays["structure"] = np.array(json.dumps(structure, sort_keys=True))
    np.savez_compressed(out, **arrays)


if __name__ == "__main__":
    main(*sys.argv[1:])
