"""The sensor's SPI protocol (SENSOR.md §6): word encoding and the software peripheral."""
