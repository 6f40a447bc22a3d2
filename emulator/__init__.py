"""Sample-level emulator of the BioTac tactile fingertip sensor.

Data flow (one module per stage, named after what it models):

    stimuli -> mechanics (fluid/skin) -> transducer (piezoresistive bridge)
            -> frontend (stage 1 -> PDC, stage 2 -> PAC) -> extrinsic noise
            -> adc (12-bit codes at the instants the host commands)

:class:`emulator.sensor.Sensor` builds only the effects a scene needs and
serves ADC codes for (channel, instant) requests; :mod:`emulator.spi` puts the
sensor's SPI protocol in front of it.
"""

from emulator.params import SensorParams
from emulator.sensor import Sensor

__all__ = ["Sensor", "SensorParams"]
