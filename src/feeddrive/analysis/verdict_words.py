"""The words a creep verdict uses: one vocabulary for both rules.  Issue 24 item 4.

Two rules judge a table-speed trace and both speak these words; the rule that gave a word is
always named beside it (``describe()`` of each rule):

* the **window rule** (:mod:`feeddrive.analysis.creep_window`, ``feeddrive simulate`` and
  ``analyze``): :data:`SMOOTH`, :data:`CREEPING` or :data:`UNSTABLE` over one steady window;
* the **limit-cycle rule** (:mod:`feeddrive.analysis.cycle_verdict`, ``feeddrive creep``,
  ``reproduce``, the explorer): the *kinds* :data:`STICK_SLIP`, :data:`OSCILLATION`,
  :data:`SMOOTH` or :data:`UNDECIDED`; the first two are :data:`CREEPING`, and a trial whose run
  diverged is :data:`UNSTABLE`.

:data:`MEANING` gives each word in one line (docs/model.md, "Verdict words", prints the same
lines; a test holds the two together).
"""

from __future__ import annotations

__all__ = ["CREEPING", "CREEPING_KINDS", "KINDS", "MEANING", "NON_SMOOTH", "OSCILLATION",
           "SMOOTH", "STICK_SLIP", "UNDECIDED", "UNSTABLE", "WINDOW_VERDICTS"]

#: the table follows the command (both rules)
SMOOTH = "smooth"
#: not smooth: stick-slip or a sustained oscillation (both rules)
CREEPING = "creeping"
#: a creeping limit cycle in which the table stops (the limit-cycle rule)
STICK_SLIP = "stick-slip"
#: a creeping limit cycle in which the table never stops (the limit-cycle rule)
OSCILLATION = "oscillation"
#: not decided yet (the limit-cycle rule)
UNDECIDED = "undecided"
#: the loop diverged (the window rule; a diverged trial's kind)
UNSTABLE = "unstable"

#: the four kinds of :func:`~feeddrive.analysis.cycle_verdict.trace_verdict`; the first two
#: are creep
KINDS = (STICK_SLIP, OSCILLATION, SMOOTH, UNDECIDED)
#: the kinds that are creep (a limit cycle)
CREEPING_KINDS = (STICK_SLIP, OSCILLATION)
#: kinds that are not smooth: the critical speed is the upper edge of the highest such band
NON_SMOOTH = (*CREEPING_KINDS, UNSTABLE)
#: the verdicts of :func:`~feeddrive.analysis.creep_window.creep_metrics`
WINDOW_VERDICTS = (SMOOTH, CREEPING, UNSTABLE)

#: each word in one line, as docs/model.md prints it
MEANING = {
    SMOOTH: "the table follows the command: the speed settles within the rule's band",
    CREEPING: "the table does not move steadily: it sticks and slips or keeps oscillating",
    STICK_SLIP: "a creeping limit cycle in which the table stops (or reverses) every cycle",
    OSCILLATION: "a creeping limit cycle in which the table never stops",
    UNDECIDED: "neither settled nor a repeating cycle yet: a longer run decides",
    UNSTABLE: "the loop diverged: the speed ran far beyond the command",
}
