"""Flows derived from a part's code text (issue 40 item 1): a part names the signals it reads
and writes in braces, and :meth:`feeddrive.model.codegen.Builder.emit` derives what each
rate, signal and named value is computed from — no second declaration beside the code.

Built on a bare :class:`~feeddrive.model.codegen.Builder` (nothing is compiled).
"""

from __future__ import annotations

import pytest

from feeddrive.model.codegen import Builder, Line


def _builder() -> Builder:
    b = Builder()
    for name in ("x", "v", "z", "i"):
        b.state(name, "m", name, "position")
    b.add_aux("u", "V", "a signal")
    b.param("k", 2.0)
    return b


def test_braces_become_slots_and_flows() -> None:
    b = _builder()
    b.emit("{w} = {v}")
    b.emit(f"{{der(x)}} = {{w}} * {b.p('k')}")
    b.emit("{u} = {x} + t")  # an unbraced t is a local, not the time: nothing read
    assert b.rhs_lines == ["w = y[1]", "dy[0] = w * P[0]", "aux[0] = y[0] + t"]
    assert b.flows == {"w": {"y:v"}, "dy:x": {"w"}, "aux:u": {"y:x"}}


def test_unbraced_locals_stand_for_what_they_were_computed_from_at_that_line() -> None:
    """A reused local (``raw`` of two loop axes) carries its last value's reads, so the
    second axis does not read the first's states."""
    b = _builder()
    b.emit("raw = {x} + {v}")
    b.emit("{der(x)} = raw")
    b.emit("raw = {z}")
    b.emit("{der(z)} = raw")
    assert b.flows == {"dy:x": {"y:x", "y:v"}, "dy:z": {"y:z"}}


def test_branches_join_and_conditions_count() -> None:
    """After an if/else a local is the union of its branches (without an else: with its value
    before the if); a value written inside an if also reads the condition."""
    b = _builder()
    b.emit("a = {x}")
    b.emit("if {i} > 0.0:")
    b.emit("    a = {v}")
    b.emit("    {der(v)} = 0.0")
    b.emit("else:")
    b.emit("    a = {z}")
    b.emit("{der(x)} = a")
    b.emit("c = {x}")
    b.emit("if 1.0 > 0.0:")
    b.emit("    c = {v}")
    b.emit("{der(z)} = c")
    # a = {x} is replaced in both branches; which branch ran depends on {i}
    assert b.flows["dy:x"] == {"y:i", "y:v", "y:z"}
    assert b.flows["dy:v"] == {"y:i"}
    assert b.flows["dy:z"] == {"y:x", "y:v"}


def test_a_line_carries_what_its_text_cannot_show() -> None:
    """A kernel that receives y and dy whole (a friction law's own states): the line adds
    its block to what its text reads, for every value it sets."""
    b = _builder()
    b.emit(Line("{f} = _law({v}, y, int(2), P, int(0), dy)", writes=("dy:z",),
                reads=("y:z",)))
    assert b.flows == {"f": {"y:v", "y:z"}, "dy:z": {"y:v", "y:z"}}


@pytest.mark.parametrize(("line", "message"), [
    ("{der(x)} = {nobody}", r"\{nobody\}: read but no part writes it"),
    ("{x} = 1.0", r"\{x\}: a state or the time is read, not written"),
    ("dy[0] = {v}", "write 'dy\\[0\\]' through a braced name"),
    ("{der(x)} = y[1]", r"reads y\[…\]; name the state or signal in braces"),
    ("{der(q)} = 0.0", "'q' is no state"),
    ("else:", "without its if"),
])
def test_hidden_or_unknown_reads_and_writes_are_refused(line: str, message: str) -> None:
    with pytest.raises(ValueError, match=message):
        _builder().emit(line)


def test_a_scope_qualifies_names_and_keeps_its_locals() -> None:
    """Inside a machine's axis scope the names are the axis' (``x.``-qualified flows), and a
    local of one axis is not another's."""
    b = Builder()
    for axis in ("p", "q"):
        with b.scope(axis):
            b.state("s", "m", "s", "position")
            b.emit("{w} = {s}")
            b.emit("{der(s)} = {w}")
    assert b.flows == {"p.w": {"y:p.s"}, "dy:p.s": {"p.w"}, "q.w": {"y:q.s"},
                       "dy:q.s": {"q.w"}}
    assert b.scoped_rhs["q"] == ["w = y[1]", "dy[1] = w"]


def test_sampled_code_resolves_braces_without_flows() -> None:
    b = _builder()
    b.emit("{der(x)} = {v}")
    b.emit("held_v = {v} + {x}", sampled=True)
    assert b.sample_lines == ["held_v = y[1] + y[0]"]
    assert b.flows == {"dy:x": {"y:v"}}
