"""Offline analysis of sensor data and estimation error: vibration (spectra, peaks, levels, clipping), what-if
replays, expressions of channels and Allan deviation (seeds 002, 003). The amplitude spectrum (seed 003) is
``groundstation.spectrum``, below the estimators that use it too."""
