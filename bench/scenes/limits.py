"""Limits of a scene that other parts check without loading the scene machinery (and the emulator behind it):
:mod:`bench.scenes.scene` re-exports them."""

#: sensors a scene can describe: the bridge firmware and the Cheetah adapter serve at most 5
MAX_SENSORS = 5
#: the sensors' SPI sides a scene's host.spi, the bridge, the Cheetah adapter and the pytest plugin choose between:
#: the software model, or the Verilog RTL under Verilator
SPI_SIDES = ("software", "rtl")
#: what each of SPI_SIDES is, for a refusal of any other value
SPI_SIDES_SAID = '"software" (the Python model) or "rtl" (the Verilog twin)'
