"""Code generators that read an assembled model's kernels: the C backend (:mod:`.c_backend`,
:mod:`.c_translate`).  Kept outside ``model/`` and ``solvers/`` on purpose: those folders'
sources name the numba cache and ``KERNEL_HASH`` (feeddrive._jit), and a change to a code
generator changes no kernel."""
