"""Shipped parameter tables (TOML: each number with its unit, source, status) and their loader."""
