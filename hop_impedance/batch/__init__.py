"""Batch analysis of many recordings (``hop-impedance batch``).

- :mod:`.inputs`      recordings from files, folders (recursive) or a manifest CSV, with labels
- :mod:`.task`        one recording -> analyze JSON + tidy rows + fits (pure; no Dask)
- :mod:`.tidy`        the stance x joint table (Parquet and CSV)
- :mod:`.population`  seed Table 1/2/3 layouts by condition, tests paired by subject, figures
- :mod:`.runner`      the job: skip rule, serial or Dask distributed execution, progress, outputs

Only :mod:`.runner` imports Dask; the numerical core knows nothing of it.
"""
