"""Parts of a drive model given as parameter sections of their own (``[acceleration_feedforward]``
…): each module registers its section class (registry group ``feeddrive.sections``); a class
with ``declare_part(b, axes) -> axes`` and ``emit_part(b)`` is assembled into the model, and
its ``schedule()`` — (field, period [s]) pairs — joins the breakpoint grid of the sampled
loops.  See docs/extending.md."""
