"""The ``rtgait`` command: one module per subcommand, parsed and dispatched by :mod:`rtgait.cli.main`.

Its modules are mapped in ``docs/architecture.md``.
"""
