"""The desktop app; the only package that imports Qt (PySide6, pyqtgraph).

    app.py             QApplication and the main window on a source (``groundstation app``)
    main_window.py     connection bar, live view, side panels, status bar; owns the session
    sessions.py        starting the demo, serial and replay sessions, with readable errors
    connection_bar.py  port list (refreshed), baud, connect, demo, open recording
    live_view.py       attitude, sensor and diagnostic tabs over a time window; pause view
    plots.py           stacked pyqtgraph plots on a shared time axis
    series.py          the plotted quantities of a growing table, as numpy arrays (no Qt)
    link_panel.py      link health with a colour warning
"""
