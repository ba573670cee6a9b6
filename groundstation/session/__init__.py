"""A session: one flight's stream from a source through the decoder and the estimators into columns.

``Pipeline`` is the whole computation (no threads, no I/O): feed it timestamped byte chunks, read
its tables. ``LiveSession`` runs a source on a reader thread, records it and feeds a pipeline
(``factory.open_session(spec)`` makes one from a source string: a port, a bridge, ``sim:``, a recording);
``replay`` feeds a recording through a fresh pipeline's ``Pipeline.feed`` chunk by chunk, as live,
so it reproduces the live estimates bit for bit; a recording opened whole (``data.load_session``)
takes the batch path (``batch.batch_replay``: columns, not chunks), which calls the pipeline's own
rules and gives the same tables (tests/session/test_batch.py).
"""
