"""A session: one flight's stream from a source through the decoder and the estimators into columns.

``Pipeline`` is the whole computation (no threads, no I/O): feed it timestamped byte chunks, read
its tables. ``LiveSession`` runs a source on a reader thread, records it and feeds a pipeline
(``factory.open_session(spec)`` makes one from a source string: a port, a bridge, ``sim:``, a recording);
``replay`` feeds a recording through a fresh pipeline. Replay and live go through the same
``Pipeline.feed``, so a replayed recording reproduces the live estimates bit for bit.
"""
