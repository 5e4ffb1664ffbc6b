"""The compiled backend: Numba's loader, keyed on every source, and its switches."""
