"""Sample-level emulator of the BioTac tactile fingertip sensor.

Data flow (one module per stage, named after what it models):

    stimuli -> mechanics (fluid/skin) -> transducer (piezoresistive bridge)
            -> frontend (stage 1 -> PDC, stage 2 -> PAC) -> extrinsic noise
            -> adc (12-bit codes at the instants the host commands)

:class:`emulator.sensor.Sensor` builds only the effects a scene needs and
serves ADC codes for (channel, instant) requests; :mod:`emulator.spi` puts the
sensor's SPI protocol in front of it.

``emulator.Sensor`` and ``emulator.SensorParams`` are imported on first use, so that importing a light
submodule (``emulator.fidelity``, ``emulator.channels``, ...) does not load the sensor and its scipy/numba stack.
"""

import importlib

#: the package's public names and the submodule each lives in (imported on first access)
_LAZY = {"Sensor": "emulator.sensor", "SensorParams": "emulator.params"}

__all__ = list(_LAZY)


def __getattr__(name: str):
    if name in _LAZY:
        value = getattr(importlib.import_module(_LAZY[name]), name)
        globals()[name] = value  # later accesses skip this function
        return value
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__():
    return sorted(set(globals()) | set(_LAZY))
