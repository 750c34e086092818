"""What a run leaves: plain data for files, result files, terminal tables and figures.

Figures are ``matplotlib.figure.Figure`` objects written with the Agg canvas: no pyplot,
so no backend is chosen for a user's own plots (a notebook keeps its own). matplotlib
takes a third of a second to import; the modules a command imports before its run
(``cli``, ``api``, ``results``, ``run_files``) import the drawing modules only where they
draw, so that a run's figures can be drawn by processes that imported them while it ran
(``run_files``)."""
