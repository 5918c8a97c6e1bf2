"""The engine: one run of an assembled drive system (:mod:`~feeddrive.engine.simulate`), what
it costs before it starts (:mod:`~feeddrive.engine.budget`) and what it returns
(:mod:`~feeddrive.engine.result`)."""
