"""A model built for one profile and re-used for another of the same type (only the
profile's slots of P and its table in T rewritten, `feeddrive.model.assemble._with_profile`)
equals the model built from scratch, field by field — the reuse is what makes a creep trial
and a linearisation skip the ~1 ms of building their model again."""

from __future__ import annotations

import dataclasses
import importlib

import numpy as np
import pytest

import feeddrive as fd
from feeddrive._kept import Kept
from feeddrive.model.reference import ConstantSpeed, SampledSpeed, SineSpeed
from feeddrive.model.replay import REPLAYS
from feeddrive.parameters import ParameterError

asm = importlib.import_module("feeddrive.model.assemble")  # the module, not the function

CASES = [
    ("wang2021", "cdfs", 0.4, [ConstantSpeed(1e-3), ConstantSpeed(2.5e-3, ramp_time=0.0),
                               ConstantSpeed(0.2e-3, ramp_time=0.3)]),
    ("wang2021", "ddfs", 0.2, [ConstantSpeed(1e-3, 16e-3), ConstantSpeed(0.5e-3, 2e-3, 0.0),
                               ConstantSpeed(-1e-3, 16e-3)]),
    ("wang2021", "ddfs", 0.4, [SineSpeed(1.56e-3, 0.0, 0.2), SineSpeed(2e-3, 16e-3, 0.2)]),
    ("wang2021-ripple", "ddfs", 0.4, [ConstantSpeed(1e-3, 16e-3), ConstantSpeed(2e-3, 30e-3)]),
    ("wang2021-drive", "cdfs", 0.6, [ConstantSpeed(1e-3), ConstantSpeed(3e-3)]),
]

_T = np.linspace(0.0, 0.5, 501)


def _sampled(speed: float, nut: float | None = None, hold: bool = False,
             t: np.ndarray = _T) -> SampledSpeed:
    """A recorded reference (a fit's experiment): a ramp to ``speed`` with a ripple."""
    v = speed * np.minimum(t / 0.1, 1.0) * (1.0 + 0.1 * np.sin(40.0 * t))
    return SampledSpeed(t, v, None if nut is None else np.full(t.size, nut), hold=hold)


#: array profiles (unhashable: a fit's records, replays) re-use their type's model too; a
#: record of another length (another table size) is built anew
ARRAY_CASES = [
    ("wang2021", "cdfs", 0.4, [_sampled(1e-3), _sampled(2e-3), _sampled(-1e-3, hold=True),
                               _sampled(3e-3, t=np.linspace(0.0, 0.3, 301))]),
    ("wang2021", "ddfs", 0.3, [_sampled(0.5e-3, 16e-3), _sampled(1e-3, 2e-3, hold=True)]),
    *[("wang2021", "cdfs", 0.4, [cls(_T, np.sin(20.0 * _T), 2e-3),
                                 cls(_T, 0.5 * np.cos(30.0 * _T), 1e-3)])
      for cls in REPLAYS.values()],  # every replay of the registry (values in its SI unit)
]


def _same(a: asm.Model, b: asm.Model) -> None:
    for f in dataclasses.fields(asm.Model):
        x, y = getattr(a, f.name), getattr(b, f.name)
        if isinstance(x, np.ndarray):
            assert x.dtype == y.dtype and x.shape == y.shape, f.name
            assert np.array_equal(x, y), f.name  # bit for bit (no NaN in these vectors)
        elif f.name == "module":
            assert x is y  # the compiled module is shared by its source hash
        else:
            assert x == y, f.name


@pytest.mark.parametrize(("preset", "drive", "position", "profiles"), CASES + ARRAY_CASES)
def test_a_reused_model_equals_the_one_built_anew(preset: str, drive: str, position: float,
                                                  profiles: list[object]) -> None:
    params = fd.preset(preset)
    first = asm.assemble(params, drive, position, "locked", profiles[0])
    for profile in profiles[1:]:
        fast = asm.assemble(params, drive, position, "locked", profile)
        full = asm._assemble(params, drive, position, "locked", profile, None)
        _same(fast, full)
        assert fast.P is not first.P and fast.T is not first.T  # never the template's arrays
    _same(asm.assemble(params, drive, position, "locked", profiles[0]), first)


def test_a_reused_model_still_refuses_a_nut_speed_on_the_cdfs() -> None:
    params = fd.preset("wang2021")
    asm.assemble(params, "cdfs", 0.3, "locked", ConstantSpeed(1e-3))
    with pytest.raises(ParameterError, match="nut_speed"):
        asm.assemble(params, "cdfs", 0.3, "locked", ConstantSpeed(1e-3, 1e-3))


def test_a_fits_records_of_one_length_build_one_model(monkeypatch: pytest.MonkeyPatch) -> None:
    """A fit simulates each experiment (an array profile: unhashable) at each parameter point;
    the model was built anew for every one (an outside look, 2026-12-07: model building was
    ~30 % of a fit's CPU).  Now the experiments of one point, records of one length, build it
    once; a record of another length, or another parameter point, builds its own."""

    built: list[object] = []
    full = asm._assemble

    def counting(*args: object) -> asm.Model:
        built.append(args[4])
        return full(*args)

    monkeypatch.setattr(asm, "_TEMPLATES", Kept(64, asm._template_bytes, asm._TEMPLATES_BYTES))
    monkeypatch.setattr(asm, "_assemble", counting)
    params = fd.preset("wang2021")
    for speed in (1e-3, 2e-3, 5e-3):
        asm.assemble(params, "cdfs", 0.4, "locked", _sampled(speed))
    assert len(built) == 1
    asm.assemble(params, "cdfs", 0.4, "locked", _sampled(1e-3, t=np.linspace(0.0, 0.3, 301)))
    assert len(built) == 2
    asm.assemble(params.replace_path("table.mass", 30.0), "cdfs", 0.4, "locked",
                 _sampled(1e-3))
    assert len(built) == 3


def test_the_kept_models_hold_a_bounded_number_of_bytes(monkeypatch: pytest.MonkeyPatch) -> None:
    """A record's profile puts its table in the model's T (an 8-kHz, 100-s record: 26 MB),
    and a fit builds a model per parameter point: the kept models are bounded in bytes
    (``_TEMPLATES_BYTES``), not only in number, so a long fit does not grow by 64 records.
    Here a bound of 1.5 MB and records of 640 kB: at most two kept, the newest; a record
    larger than the bound is used but not kept."""

    monkeypatch.setattr(asm, "_TEMPLATES", Kept(64, asm._template_bytes, 1_500_000))
    params = fd.preset("wang2021")
    t = np.linspace(0.0, 2.0, 20_001)
    masses = (20.0, 21.0, 22.0, 23.0, 24.0)
    for mass in masses:
        asm.assemble(params.replace_path("table.mass", mass), "cdfs", 0.4, "locked",
                     _sampled(1e-3, t=t))
    kept = list(asm._TEMPLATES.values())
    assert len(kept) == 2
    assert sum(m.P.nbytes + m.T.nbytes for m, _, _ in kept) <= 1_500_000
    assert [k[0].table.mass for k in asm._TEMPLATES] == [23.0, 24.0]
    big = np.linspace(0.0, 5.0, 50_001)  # 1.6 MB of table
    model = asm.assemble(params, "cdfs", 0.4, "locked", _sampled(1e-3, t=big))
    assert model.T.nbytes > 1_500_000
    assert (params, "cdfs", 0.4, "locked", SampledSpeed, None) not in asm._TEMPLATES
    assert len(asm._TEMPLATES) == 2


def test_threads_share_the_kept_models_without_error(monkeypatch: pytest.MonkeyPatch) -> None:
    """The explorer runs its jobs on threads.  Two threads reading and evicting the kept
    models at once raised ``KeyError`` (a key evicted between one thread's look-up and its
    move to the end) or "OrderedDict mutated during iteration" — 3 of 3 runs of this test
    before the lock; the thread switch made frequent here to meet the race."""
    import sys
    import threading

    monkeypatch.setattr(asm, "_TEMPLATES", Kept(2, asm._template_bytes, asm._TEMPLATES_BYTES))
    params = fd.preset("wang2021")
    sets = [params.replace_path("table.mass", 20.0 + k) for k in range(6)]
    errors: list[str] = []

    def work(seed: int) -> None:
        rng = np.random.default_rng(seed)
        try:
            for _ in range(60):
                asm.assemble(sets[int(rng.integers(6))], "cdfs", 0.4, "locked", _sampled(1e-3))
        except Exception as err:  # noqa: BLE001 - every error is the finding
            errors.append(repr(err))

    interval = sys.getswitchinterval()
    sys.setswitchinterval(1e-6)
    try:
        threads = [threading.Thread(target=work, args=(seed,)) for seed in range(4)]
        for th in threads:
            th.start()
        for th in threads:
            th.join()
    finally:
        sys.setswitchinterval(interval)
    assert errors == []
    assert len(asm._TEMPLATES) <= 2
