"""The problem file as plain data: its schema and dotted-key overrides."""
