"""Exports of a session's columns: CSV and Parquet here (``export_csv``, ``export_parquet``)."""
