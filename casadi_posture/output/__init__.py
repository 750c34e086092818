"""What a run leaves: plain data for files, result files, terminal tables and figures."""
