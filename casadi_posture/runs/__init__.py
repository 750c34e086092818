"""Many solves at once: solver comparison, batches and what-if grids."""
