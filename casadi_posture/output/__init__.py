"""What a run leaves: plain data for files, result files, terminal tables and figures
(drawn with matplotlib's Agg backend into files)."""

import matplotlib

matplotlib.use("Agg")
