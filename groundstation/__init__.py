"""Ground station for small quadrotors: telemetry decoding, attitude estimation, recording, replay, export.

Everything outside ``groundstation.ui`` runs without a display and never imports Qt.
"""

__version__ = "0.1.0"
