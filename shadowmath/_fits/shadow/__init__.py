""":func:`fit_shadow`: the door (:mod:`._door`), the driver (:mod:`._driver`, run in the array
form :mod:`._arrays` or the compiled form :mod:`._compiled`), the result
(:mod:`._result`); the spot casters' selection, the prepared fit and the optimized fit."""
