"""Sweeps over scenario variants: the spec (:mod:`~rtgait.sweep.spec`), the results store
(:mod:`~rtgait.sweep.store`), the pendulum level in-process and batched (:mod:`~rtgait.sweep.pendulum`), physics
cases in worker processes or on Dask (:mod:`~rtgait.sweep.executors`), and the ``rtgait sweep`` command
(:mod:`~rtgait.cli.sweep`). See ``docs/sweeps.md``."""
