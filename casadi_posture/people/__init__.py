"""Virtual workers drawn from measured distributions, for population runs."""
