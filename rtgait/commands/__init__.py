"""The ``rtgait`` subcommands, one module each; :mod:`rtgait.cli` parses and dispatches."""
