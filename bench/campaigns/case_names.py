"""The fault campaign's faults and scenes by name, with what each fault's correct reaction is and what each scene
holds: what ``biotac-bench campaign --help`` lists and ``--faults`` / ``--scenes`` accept.

This module imports nothing.  :mod:`bench.campaigns.faults` builds the heavy objects — each fault's bench settings,
schedule and check, each scene's stimuli (the emulator) — keyed by these names, and takes each fault's expected
reaction from here: one source of truth.  ``bench/tests/test_cli_followups.py`` checks that the two agree (the same
names in the same order, and each scene's description names its stimuli as they are built)."""

#: fault name -> what a correct firmware and driver do, in the order the campaign runs them
FAULT_EXPECTED = {
    "none": "no errors, no drops, nothing flagged; before the first stimulus every code in its resting band",
    "unplug_replug": "sensor 2 lost within 2 frames, found again within 1 s",
    "parity_errors": "every sample flagged, counted",
    "miso_stuck": "stuck sensor treated as absent",
    "brownout_reset": "a reset between command and read: that sample flagged (error word), at most two, sensor kept",
    "cs_glitch": "chip select toggled with no clock edges: ignored, no errors",
    "serial_corruption": "CRC errors counted, resync, clean frames",
    "serial_loss": "dropped frames counted from sequence numbers",
    "fluid_leak": "resting PDC falls as the pressure-volume curve predicts",
}

#: campaign scene name -> its stimuli for sensor 1 ("count × kind: ...", times from power-on), in campaign order
SCENE_DESCRIPTIONS = {
    "rest": "no stimulus (at rest)",
    "taps": "2 × Tap: 0.5 N at 0.5 s, 1 N at 1 s",
    "sphere_drops": "4 × SphereDrop: a 1 mm steel bearing landing at 0.4, 0.7, 1 and 1.3 s",
    "press": "1 × Touch: 1 N over E17 from 0.3 s (0.2 s ramps, 0.6 s hold)",
}

#: frames a case reads (each the bridge firmware's default 44-slot frame, 10 ms); a scene file's case reads more
#: if the scene lasts longer (:attr:`bench.campaigns.scene_files.CampaignScene.frames`)
CASE_FRAMES = 150
#: the longest scene file a case streams (s): a case is a step of a CI job, not a long recording
CASE_MAX_S = 30.0


def is_scene_file(entry: str) -> bool:
    """Whether a ``campaign --scenes`` entry names a scene file — a path with a folder, or a name ending in
    ``.toml`` (a file here, else the shipped scene of that name) — rather than one of :data:`SCENE_DESCRIPTIONS`."""
    return "/" in entry or entry.endswith(".toml")


#: the SPI buses a campaign runs over (``campaign --spi``): the software model, or the Verilog RTL in the C++ harness
SPI_BUSES = ("software", "rtl")

#: faults whose effect the RTL bus cannot carry yet -> why (none now: every fault runs over either bus; a fault
#: added to the campaign that the RTL cannot carry is listed here, and refused over the RTL by name)
NEEDS_SOFTWARE_SPI: dict[str, str] = {}


def check_bus(faults, spi: str) -> None:
    """ValueError unless every fault of ``faults`` (names) can run over the SPI bus ``spi`` (one of
    :data:`SPI_BUSES`): naming each one that cannot, why, and what to run instead."""
    if spi not in SPI_BUSES:
        raise ValueError(f"spi = {spi!r}: one of {', '.join(SPI_BUSES)}")
    if spi == "software":
        return
    faults = list(faults)
    refused = [f for f in faults if f in NEEDS_SOFTWARE_SPI]
    if refused:
        rest = [f for f in faults if f not in NEEDS_SOFTWARE_SPI]
        raise ValueError(
            f"{'; '.join(f'{f} needs the software SPI bus: {NEEDS_SOFTWARE_SPI[f]}' for f in refused)}. Run "
            f"{'it' if len(refused) == 1 else 'them'} with --spi software"
            + (f", and the others over the RTL with --faults {','.join(rest)}" if rest else ""))
