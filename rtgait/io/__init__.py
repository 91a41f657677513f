"""Run outputs: the files a planned walk, a pendulum run and a walk in physics write.

Its modules are mapped in ``docs/architecture.md``.
"""
