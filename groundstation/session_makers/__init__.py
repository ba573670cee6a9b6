"""The session's makers: what turns a source into the product (``session.product.SessionData``) that the
window and the exports read. ``pipeline.Pipeline`` (no threads, no I/O: timestamped byte chunks in, tables
out; ``mavlink_front`` is its MAVLink front-end), run live by ``live.LiveSession`` (``factory.open_session``
makes one from a source string) and over a recording by ``replay``; a file opened whole (``load.load_session``)
takes the batch path (``batch.batch_replay``, its estimators run by ``estimate_run``) or its format's
loader (``loaders``; a flight log's: ``flight_log_session``). Nothing below this folder imports it.
Docs: docs/session.md.
"""
