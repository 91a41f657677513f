"""Run outputs: the files a planned walk, a pendulum run and a walk in physics write."""
