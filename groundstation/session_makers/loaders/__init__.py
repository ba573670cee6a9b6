"""The loaders of the file formats that fill the session product themselves (``formats`` registers
them by name): a recording and a dataset CSV. A flight log's is ``session_makers.flight_log_session.load_log``."""
