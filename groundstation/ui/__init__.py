"""The desktop app; the only package that imports Qt (PySide6, pyqtgraph).

    app.py                QApplication and the main window on a source (``groundstation app``)
    first_frame.py        the window's first paint (the source opens after it) and the start's stopwatch
    main_window.py        menus and keys, connection bar, live view, side panels, status bar; owns the session
    connection_bar.py     port list (refreshed), baud, connect, demo, open recording, export
    replay_bar.py         play/pause, step, speed, seek slider
    live_view.py          attitude, sensor, diagnostic, heading, position and channel tabs over a time window; pause view
    channels.py           plot any channel: the session's tables and columns (one catalogue), plot panes
    position_view.py      the position tab: GPS track, height over time, the newest fix in numbers
    plots.py              stacked pyqtgraph plots on a shared time axis, crosshair, gap shading
    series.py             the plotted quantities of a growing table, as numpy arrays (no Qt)
    navigation.py         compass, barometer, GPS and fused-position quantities; the newest heading (no Qt)
    attitude_indicator.py artificial horizon, the 3D view beside it, pitch/roll/yaw/heading readouts
    attitude_3d.py        the airframe turned by the quaternion, drawn with QPainter (no OpenGL)
    event_console.py      the session's events with their times; a click shows that moment
    link_panel.py         link health with a colour warning
    estimator_panel.py    comparison estimators shown, live tuning, defaults; a replay's what-if estimators and settings
    uplink_panel.py       firmware mode, AHF parameters, CONFIG, gyro calibration; ACK or timeout
    export_dialog.py      format, file, range, rate; progress and Cancel
    export_job.py         the export in a worker thread (no Qt)
"""
