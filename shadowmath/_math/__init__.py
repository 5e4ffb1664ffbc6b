"""Per-entry formulas (one source for every backend), their loops, and the topics' cores."""
