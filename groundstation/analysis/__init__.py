"""Offline analysis of sensor data and estimation error: spectra (seed 003) and Allan deviation (seeds 002, 003)."""
