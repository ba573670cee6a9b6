"""A session: one flight's stream from a source through the decoder and the estimators into tables.

The product (``product.SessionData``: tables described by ``catalogue``, events, link figures,
config, settings) is what every reader reads; ``view`` is what the window reads of a session, live
or played back. Its makers: ``pipeline.Pipeline`` (no threads, no I/O: timestamped byte chunks in,
tables out), run live by ``live.LiveSession`` (a reader thread, a recording; ``factory.open_session``
makes one from a source string) and over a recording by ``replay`` (chunk by chunk, as live, so it
reproduces the live estimates bit for bit); a recording opened whole (``load.load_session``) takes the
batch path (``batch.batch_replay``: columns, not chunks), which calls the pipeline's own rules and
gives the same tables (tests/session/test_batch.py). ``load`` opens any file whole (a recording, a
dataset, a flight log) and ``playback`` plays it back. Docs: docs/session.md.
"""
