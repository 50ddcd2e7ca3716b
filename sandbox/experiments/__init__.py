"""Experiments: many trials, their statistics and the paper's tables.

- :mod:`.plan`       what a sweep runs: cases (paper's or a grid file) and trials
- :mod:`.trials`     one trial, as plain data a worker can run
- :mod:`.executors`  local worker processes or a Dask cluster, retries
- :mod:`.storage`    the trial files of a sweep folder, resume
- :mod:`.sweep`      ``phototaxis sweep``
- :mod:`.report`     ``phototaxis report``: tables, tests, figures, report.md
- :mod:`.stats`      summaries and Kolmogorov-Smirnov tests
- :mod:`.figures`    the paper's figures
- :mod:`.reference`  the paper's and the authors' program's numbers
"""
