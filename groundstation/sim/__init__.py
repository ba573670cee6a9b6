"""The flight simulator: truth profiles, an MPU-6050 model, simulated firmware and a radio link.

    settings.py   what a flight is asked to be (the board's and vibration settings, profile names), without the simulator
    profiles.py   seeded truth trajectories (attitude, body rate, linear motion), exact at any instant
    imu.py        MPU-6050 error model -> int16 counts (settings default to the datasheet)
    extra_sensors.py optional magnetometer, barometer and GPS models
    firmware.py   the flight board: sampling clock, onboard AHF (float32), frames, commands
    link.py       the radio + USB link: loss (independent, bursts), bit errors, truncation, latency,
                  batching, port drop-outs; reports exactly what it injected
    stream.py     firmware + link in simulated time: the bytes a serial port would deliver
    pty_bridge.py a POSIX pseudo-terminal carrying that stream in real time
    port.py       the same stream as an in-process, pyserial-like port (Windows has no pty)
"""
