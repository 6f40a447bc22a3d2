"""Limits of a scene that other parts check without loading the scene machinery (and the emulator behind it):
:mod:`bench.scenes.scene` re-exports them."""

#: sensors a scene can describe: the bridge firmware and the Cheetah adapter serve at most 5
MAX_SENSORS = 5
#: the sensors' SPI sides a scene's host.spi, the bridge, the Cheetah adapter and the pytest plugin choose between:
#: the software model, or the Verilog RTL under Verilator
SPI_SIDES = ("software", "rtl")
#: what each of SPI_SIDES is, for a refusal of any other value
SPI_SIDES_SAID = '"software" (the Python model) or "rtl" (the Verilog twin)'
#: the largest seed a scene's [scene] seed, a command's --seed and the pytest plugin's seeds (--biotac-seed, the ini
#: value biotac_seed, the marker's and a factory call's seed=) take: numpy's signed 64-bit integer, so that sensor
#: k's seed (seed + k - 1, k ≤ MAX_SENSORS) still fits the unsigned one a sensor's seeding takes
MAX_SEED = 2**63 - 1
#: what a seed may be, for the plugin's refusal of any other value (every route the same words)
SEED_SAID = f"a seed, a whole number from 0 to {MAX_SEED} (e.g. 7)"


def seed_problem(value) -> str | None:
    """Why ``value`` is not a seed — an integer (numpy's too, not a bool), a whole float, or decimal digits, from 0
    to :data:`MAX_SEED` — in the words of :data:`SEED_SAID`, else None."""
    import math
    import numbers

    if isinstance(value, str):
        whole = int(value) if value.isascii() and value.isdecimal() else None
    elif isinstance(value, numbers.Integral) and not isinstance(value, bool):
        whole = int(value)
    elif isinstance(value, numbers.Real) and not isinstance(value, bool) and math.isfinite(value) \
            and float(value).is_integer():
        whole = int(value)
    else:
        whole = None
    return None if whole is not None and 0 <= whole <= MAX_SEED else f"{value!r}: {SEED_SAID}"
