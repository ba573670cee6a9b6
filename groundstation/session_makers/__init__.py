"""The session's makers: what turns a source into the product (``session.product.SessionData``) that the
window and the exports read. ``pipeline.Pipeline`` (no threads, no I/O: timestamped byte chunks in, tables
out; ``mavlink_front`` is its MAVLink front-end), run live by ``live.LiveSession`` (a reader thread, a
recording; ``factory.open_session`` makes one from a source string) and over a recording by ``replay``
(chunk by chunk, as live, so it reproduces the live estimates bit for bit). A recording opened whole
(``load.load_session``, which opens any file whole) takes the batch path (``batch.batch_replay``: columns,
not chunks, its estimators run by ``estimate_run``), which calls the pipeline's own rules and gives the
same tables (tests/session/test_batch.py); another file takes its format's loader (``loaders``; a flight
log's: ``flight_log_session``). The window and the exports never import this folder. Docs: docs/session.md.
"""
