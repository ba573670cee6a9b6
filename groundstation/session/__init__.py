"""The product of a session, what every reader reads, whatever made it: ``product.SessionData`` (tables
described by ``session_parts.catalogue``, events, link figures, config, settings); ``view``, what the
window reads of a session, live or played back; and ``playback``, a file's computed session played back
as if it were arriving. What makes it is in ``session_makers/``, what it is built of in
``session_parts/``. Docs: docs/session.md.
"""
