"""The fits: fit_shadow's boundary, its array and compiled paths, the spec, the optimized fit."""
