"""A driver you can read (issue 42 item 3): the driver's pieces — Jacobian and modal
analysis, stiffness estimate and method switching, step-size controller, dense output, output
samples, bound checks, next event, the memory carried between calls
(:data:`feeddrive.solvers.driver.PIECES`) — are functions of at most 150 lines in the text each
build compiles: numba's (the step functions written in, the pieces inlined by numba) and the C
translation's (calling them).  Both drivers are within the limit in both texts: their work
arrays made by their caller, the dense driver's step attempt a piece, numba's drivers compiled
without numba's reference counting, which made its inlining of the pieces cost (they were
written into its text), its two pieces of more arguments than numba's inliner takes passed a
tuple."""

from __future__ import annotations

import ast
import dis
import types

import pytest

from feeddrive.backends import c_engine
from feeddrive.solvers import driver, driver_text, shared

LIMIT = 150  # [lines] of a function's text, its signature and docstring included


def lengths(text: str) -> dict[str, int]:
    """Lines of every function defined in ``text``."""
    tree = ast.parse(text)
    return {n.name: n.end_lineno - n.lineno + 1 for n in ast.walk(tree)
            if isinstance(n, ast.FunctionDef) and n.end_lineno is not None}


@pytest.mark.parametrize("inline", [True, False], ids=["numba", "c"])
@pytest.mark.parametrize("name", driver.PIECES)
def test_every_piece_is_at_most_150_lines(name: str, inline: bool) -> None:
    got = lengths(driver_text.piece_source(name, inline))
    assert set(got) == {name}
    assert got[name] <= LIMIT


def called(text: str) -> set[str]:
    return {n.func.id for n in ast.walk(ast.parse(text)) if isinstance(n, ast.Call)
            and isinstance(n.func, ast.Name)}


def test_the_numba_module_holds_the_pieces_inlined_into_the_drivers() -> None:
    text = "\n\n\n".join(shared.solver_sources())
    for name in driver.PIECES:
        assert f"@inline_kernel\ndef {name}(" in text
    # every piece called, none written into a driver (numba inlines them: the drivers are
    # compiled without its reference counting, benchmarks/README.md, "the driver split")
    assert called(text) & set(driver.PIECES) == set(driver.PIECES)
    for use in driver.NUMBA_NRT_FREE:
        assert f"@nrt_free_kernel\ndef {use}(" in text


def test_the_c_drivers_call_every_piece() -> None:
    reached = set().union(*(called(c_engine.lowered_source(use)[0]) for use in c_engine.USES)
                          ) & set(driver.PIECES)
    more = reached
    while more:  # and the pieces those call
        more = set().union(*(called(driver_text.piece_source(p, False)) for p in more)) & set(
            driver.PIECES) - reached
        reached |= more
    assert reached == set(driver.PIECES)


def test_the_fmu_driver_is_at_most_150_lines() -> None:
    for inline in (True, False):
        assert lengths(driver_text.source("advance", inline))["advance"] <= LIMIT


@pytest.mark.parametrize(("use", "build"), [
    ("integrate", "c"), ("integrate", "numba"), ("integrate_dense", "c"),
    ("integrate_dense", "numba"),
])
def test_the_drivers_are_at_most_150_lines(use: str, build: str) -> None:
    text = driver_text.source(use) if build == "numba" else c_engine.lowered_source(use)[0]
    # C: the dense driver's entry, which makes its work arrays, and the driver it calls
    assert lengths(text)[use] <= LIMIT and max(lengths(text).values()) <= LIMIT


def test_numbas_inliner_takes_every_call_in_the_numba_module() -> None:
    """numba's inliner refuses a call CPython makes with ``*args`` (``CALL_FUNCTION_EX``, more
    than 30 positional arguments): none in the shared drivers' module as numba compiles it
    (the model's arguments added), the two pieces of more parameters than
    ``driver_text.NUMBA_ARGS`` taking their later ones as a tuple."""
    text, _ = shared.model_arguments("\n\n\n".join(shared.solver_sources()))
    codes = [compile(text, "<shared drivers>", "exec")]
    seen = set()
    while codes:
        code = codes.pop()
        seen.add(code.co_name)
        ops = {i.opname for i in dis.get_instructions(code)}
        assert "CALL_FUNCTION_EX" not in ops, code.co_name
        codes += [c for c in code.co_consts if isinstance(c, types.CodeType)]
    assert {"integrate_dense", "step_attempt", "switch_method"} <= seen
    assert driver_text.bundled_pieces() == {"step_attempt", "switch_method"}
    got = lengths(text)
    for name in driver_text.bundled_pieces():
        assert f"def {name}(" in text and got[name] <= LIMIT


def test_numbas_dense_driver_allocates_nothing_and_writes_into_its_callers_arrays() -> None:
    """Compiled without numba's runtime (``driver.NUMBA_NRT_FREE``), the drivers and the
    pieces they inline make no array: no ``np.`` call, no copy, no slice assignment (which
    numba may do through a copy), the outputs and statistics written into the caller's
    arrays."""
    assert driver.NUMBA_NRT_FREE == ("integrate", "integrate_dense")
    text = "\n\n".join(driver_text.source(use) for use in driver.NUMBA_NRT_FREE)
    for fn in ast.parse(text).body:
        assert isinstance(fn, ast.FunctionDef)
        assert [a.arg for a in fn.args.args][-1] == driver_text.STATS_OUT
    pieces = called(text) & set(driver.PIECES)
    while True:  # and the pieces those call
        more = set().union(*(called(driver_text.piece_source(p)) for p in pieces)) & set(
            driver.PIECES) - pieces
        if not more:
            break
        pieces |= more
    for source in (text, *(driver_text.piece_source(p) for p in pieces)):
        for node in ast.walk(ast.parse(source)):
            if isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute):
                assert ast.unparse(node.func.value) != "np" and node.func.attr != "copy", \
                    ast.unparse(node)
            if isinstance(node, ast.Subscript) and isinstance(node.ctx, ast.Store):
                assert ":" not in ast.unparse(node.slice), ast.unparse(node)
            assert not (isinstance(node, ast.Return) and isinstance(node.value, ast.Tuple)
                        and any(isinstance(e, ast.Subscript) and isinstance(e.slice, ast.Slice)
                                for e in node.value.elts))
    assert {"step_attempt", "outputs_inside", "output_row", "land_crossing"} <= pieces


def test_the_numba_text_copies_rows_and_bundles_arguments_as_the_c_text_does_not() -> None:
    """numba's text of a piece (``driver_text.numba_text``): a row written element by element
    and
    the later arguments of a piece of many as one tuple; the C text as written."""
    assert "y_out[i_out, :] = y" in driver_text.piece_source("output_row", False)
    numba = driver_text.piece_source("output_row")
    assert "y_out[i_out, :]" not in numba and "y_out[i_out, j_col] = y[j_col]" in numba
    attempt = ast.parse(driver_text.piece_source("step_attempt")).body[0]
    params = [a.arg for a in attempt.args.args]
    assert len(params) == driver_text.BUNDLE_FROM + 1 and params[-1] == driver_text.BUNDLE
    plain = ast.parse(driver_text.piece_source("step_attempt", False)).body[0]
    assert len(plain.args.args) == 49


@pytest.mark.parametrize("use", c_engine.USES)
def test_the_lowered_texts_name_the_callers_arrays_alike(use: str) -> None:
    """numba's dense driver and the C build's drivers are lowered by one function
    (``driver_text.lower_outputs``): the statistics' length the numba build's caller allocates
    is
    the text's, and the engine's names for the caller's arrays are the driver's."""
    assert driver.N_STATS[use] == c_engine.lowered_source(use)[1]
    assert (c_engine.OUTPUTS, c_engine.STATS, c_engine.STATS_OUT) == (
        driver_text.OUTPUTS, driver_text.STATS, driver_text.STATS_OUT)
    if use in driver.NUMBA_NRT_FREE:  # numba's text writes as many
        written = [n for n in ast.walk(ast.parse(driver_text.source(use)))
                   if isinstance(n, ast.Subscript) and isinstance(n.ctx, ast.Store)
                   and ast.unparse(n.value) == driver_text.STATS_OUT]
        assert len(written) == driver.N_STATS[use]
