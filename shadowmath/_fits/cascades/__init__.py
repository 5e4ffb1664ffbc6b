""":func:`fit_cascades` (:mod:`._fit`: door, drivers and result), the splits, the LiSPSM warp and
the fitted orientation."""
