"""Files in and out: where an output may be written (:mod:`~feeddrive.io.outputs`), the result
writers (:mod:`~feeddrive.io.results`), the measured-data readers (:mod:`~feeddrive.io.measured`)
and the checked JSON store of computed results (:mod:`~feeddrive.io.json_store`)."""
