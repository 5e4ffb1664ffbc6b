""":func:`fit_cascades` (its door :mod:`._door`, driver :mod:`._driver` and result
:mod:`._result`), the splits, the LiSPSM warp and the fitted orientation."""
