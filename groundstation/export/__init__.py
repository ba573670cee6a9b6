"""Exports of a session (``session.product.SessionData``), read from its tables: CSV and Parquet
(``tabular.write_csv``, ``write_parquet``) of the columns ``columns.export_columns`` gives, the Excel
workbook (``excel.write_workbook``), and ``request``: the one way the CLI and the app's dialog ask for one."""
