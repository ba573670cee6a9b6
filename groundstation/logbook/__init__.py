"""A folder of logs at once: ``groundstation evaluate DIR --out OUT`` (and ``report DIR``).

Engineers keep hundreds of logs; a lab thousands. Every recording and flight log under a folder is opened
as the app opens it (``session_makers.load.load_session``), one process per log on every core (or the tasks of a
Dask cluster), and the results go to one Parquet dataset that DuckDB or pandas read without loading all
of it:

- ``OUT/logs.parquet``: a row per log and estimator (``logbook.summary.LOG_COLUMNS``);
- ``OUT/tables/<table>/log_id=<id>/part-0.parquet``: each log's tables, partitioned by log (Hive style);
  ``<table>`` is the table's name as a safe folder name (``names.path_name``), the name in the file's metadata.
"""

# One log's time at most in a folder run (``--time-limit``): the slowest shared log (a 4 MB SITL .tlog)
# takes 42 s. Here, not in ``folder``: the commands' help names it without importing numpy.
DEFAULT_LIMIT_S = 600.0
