"""The public boundary: converting and checking arguments once, and the one table of checks."""
