"""Exports of a session (``session.product.SessionData``), read from its tables: CSV and Parquet
(``tabular.write_csv``, ``write_parquet``) of the columns ``columns.export_columns`` gives, a stretch of rows at a
time (``columns.export_stretches``: the writer's memory does not grow with the session), the Excel
workbook (``excel.write_workbook``), the MCAP file (``mcap_file``), and ``request``: the export formats' registry
(``FORMATS``) and the one way the CLI and the app's dialog ask for an export."""
