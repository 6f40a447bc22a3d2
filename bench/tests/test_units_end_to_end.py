"""Sensor units and variants end to end (issue 10, items 1, 5 and 6 follow-through): a host reads each unit's own
serial number, an SP finger in a run records its 54-slot frame, sphere drops in scenes are Hertz impacts of the
unit's skin, and a sliding run can be redone into its folder with --force."""

from __future__ import annotations

import numpy as np
import pytest

from bench.scenes.scene import parse_scene_text
from bench.tests.cli_runs import run_cli
from bench.tests.host_benches import cheetah_adapter, read_serial, run_firmware
from emulator.spi.model import PROP_SERIAL, SELECT_CODE, default_properties, variant_serial
from emulator.units import serial_for

#: two drawn units and the nominal one; sensor 3 is an SP drawn from unit 5
UNITS_SCENE = ('[scene]\nname = "units"\nduration_s = 0.2\n[sensor]\nunit = 17\n'
               '[[sensors]]\nindex = 2\nunit = 18\n[[sensors]]\nindex = 3\nunit = "nominal"\n'
               '[[sensors]]\nindex = 4\nunit = 5\nvariant = "biotac-sp"\n')


def test_an_sp_units_serial_starts_btsp_and_others_are_unchanged():
    assert variant_serial("BTU0000000000005", "biotac-sp") == "BTSP000000000005"
    assert variant_serial("BTU0000000000005", "biotac") == "BTU0000000000005"
    assert variant_serial("BTSP01UNIT000042", "biotac-sp") == "BTSP01UNIT000042"
    assert variant_serial("BTX", "biotac-sp") == "BTSPX"


def test_the_serial_an_sp_answers_gives_back_its_unit():
    """An SP of unit 17 answers BTSP000000000017 (record.json, the firmware's detection): that serial, given back as
    a unit to reproduce the sensor, was hashed into another unit.  It is unit 17 again; other BTSP serials (the
    nominal SP's default) still seed the draw from their text."""
    from emulator.units import unit

    for seed in (0, 5, 17, 2147483647):
        answered = variant_serial(serial_for(seed), "biotac-sp")
        assert unit(answered).seed == seed and unit(answered).params == unit(seed).params, answered
    assert unit("BTSP01EMU0000001").seed not in (None, 1)
    with pytest.raises(ValueError, match="above"):
        unit("BTSP999999999999")
    sc = parse_scene_text('[scene]\nname = "again"\nduration_s = 0.2\n[sensor]\nvariant = "biotac-sp"\n'
                          'unit = "BTSP000000000017"\n')
    from bench.hosts.scene_sensors import sensors_from_scene

    assert sensors_from_scene(sc, 1)[1].params == unit(17).params


def test_a_biotac_given_an_sp_serial_is_refused_where_it_is_given():
    """An SP's serial ("BTSP...", what a host tells an SP by) given to a 19-electrode sensor made it answer that
    serial: the bridge firmware took it for an SP and asked it for E20..E24 in every frame (5 error words each).
    A scene ([sensor] and [[sensors]]), a port and the plugin's sensors refuse it, naming the unit to give instead."""
    from bench.errors import SceneError
    from bench.pytest_plugin.fixtures import one_sensor
    from emulator.sensor import Sensor
    from emulator.spi.model import SensorPort

    head = '[scene]\nname = "x"\nduration_s = 0.2\n'
    hint = r'sensor.unit = "BTSP000000000017": .*"biotac" \(E1..E19\): give variant = "biotac-sp", or unit = 17'
    with pytest.raises(SceneError, match=hint):
        parse_scene_text(head + '[sensor]\nunit = "BTSP000000000017"\n')
    with pytest.raises(SceneError, match=r'sensors\[0\].unit = "BTSP01UNIT000042": .*not starting "BTSP"'):
        parse_scene_text(head + '[[sensors]]\nindex = 2\nunit = "BTSP01UNIT000042"\nvariant = "biotac"\n')
    sp = parse_scene_text(head + '[sensor]\nunit = "BTSP000000000017"\nvariant = "biotac-sp"\n')
    assert (sp.unit, sp.serial) == ("17", "BTSP000000000017")  # an SP may answer it
    sensor = Sensor(channels_read=["PDC"])
    sensor.serial = "BTSP000000000017"
    with pytest.raises(ValueError, match='is a "biotac"'):
        SensorPort(sensor)
    with pytest.raises(ValueError, match='is a "biotac"'):
        one_sensor("BTSP000000000017")
    assert one_sensor("BTSP000000000017", "biotac-sp").params == one_sensor(17).params


@pytest.mark.firmware  # builds the Cheetah library
def test_each_unit_in_a_scene_reports_its_own_serial_through_the_cheetah_path(monkeypatch):
    from bench.hosts.scene_sensors import sensors_from_scene

    sc = parse_scene_text(UNITS_SCENE)
    with cheetah_adapter(monkeypatch, 4, sensors=sensors_from_scene(sc, 4)) as (_, lib, h):
        got = {k: read_serial(lib, h, SELECT_CODE[k]).split(b"\x00")[0] for k in (1, 2, 3, 4)}
    assert got[1] == serial_for(17).encode() and got[2] == serial_for(18).encode()
    assert got[3] == b"BT0101EMU0000003" == default_properties(3)[PROP_SERIAL][0]  # nominal: the port's default
    assert got[4] == b"BTSP000000000005"  # an SP unit: still recognisably an SP


@pytest.mark.firmware
def test_the_bridge_firmware_recognises_an_sp_unit_by_its_serial():
    from bench.hosts.scene_sensors import sensors_from_scene

    status = run_firmware(sensors_from_scene(parse_scene_text(UNITS_SCENE), 4), 0.05).status
    assert status.sp_mask == 0b1000  # only sensor 4, the SP unit


# --- a BioTac SP's default frame through run -----------------------------------------------------------------------
SP_RUN = ('[scene]\nname = "sp"\nduration_s = 0.3\n[sensor]\nvariant = "biotac-sp"\nunit = 5\n'
          '[[sensors]]\nindex = 2\nvariant = "biotac-sp"\n'
          '[[stimulus]]\nkind = "touch"\nelectrode = "E22"\nstart_s = 0.1\nforce_N = 1.0\nramp_s = 0.05\n'
          'hold_s = 0.1\n'  # the touch ends (0.3 s) with the scene: a stimulus must end within it
          '[noise]\nadc = false\nspi_coupling = false\n')


def test_run_of_an_sp_records_e20_to_e24_from_its_54_slot_frame():
    from bench.running.runner import read_channel_names, run_scene
    from emulator.channels import variant

    sc = parse_scene_text(SP_RUN)
    assert [f"E{k}" for k in range(20, 25)] == [n for n in read_channel_names(sc) if n in
                                                 {"E20", "E21", "E22", "E23", "E24"}]
    rec = run_scene(sc, progress=False)
    assert rec.status == "ok", rec.error
    frames = round(0.3 * 4400) // 54
    for k, r in ((1, rec), (2, rec.sensors[2])):
        assert set(r.channels) == set(variant("biotac-sp").frame_names), k
        for n in ("E1", "E20", "E24", "PDC"):
            assert len(r.channels[n].codes) in (frames, frames + 1), (k, n)  # once per 54 slots
            assert (r.channels[n].status == 0).all() and (r.channels[n].codes > 100).all()
    e22 = rec.channels["E22"]
    assert abs(float(e22.codes[e22.times > 0.2].mean()) - float(e22.codes[e22.times < 0.09].mean())) > 50


def test_a_scene_checks_an_sp_frame_and_accepts_its_electrodes_in_the_host_sequence():
    from bench.errors import SceneError

    head = '[scene]\nname = "s"\nduration_s = {d}\n[sensor]\nvariant = "{v}"\n'
    fifty_slots = 50 / 4400  # the 44-slot frame is read whole, the SP's 54 slots are not
    parse_scene_text(head.format(d=fifty_slots, v="biotac"))
    with pytest.raises(SceneError, match="TAC, TDC of the host sequence .54 slots."):
        parse_scene_text(head.format(d=fifty_slots, v="biotac-sp"))
    sc = parse_scene_text(head.format(d=0.1, v="biotac-sp") + '[host]\nsequence = ["E22", "PAC"]\n')
    assert sc.sequence == ["E22", "PAC"]
    with pytest.raises(SceneError, match=r'host.sequence\[0\] = "E22".*biotac-sp'):
        parse_scene_text(head.format(d=0.1, v="biotac") + '[host]\nsequence = ["E22", "PAC"]\n')


def test_the_run_command_stores_and_plots_an_sps_e20_to_e24(tmp_path):
    import h5py

    scene = tmp_path / "sp.toml"
    scene.write_text(SP_RUN)
    out = tmp_path / "out"
    r = run_cli("run", scene, "--out", out, "--quiet", timeout=300)
    assert r.returncode == 0, r.stderr
    for folder in (out, out / "sensor2"):
        with h5py.File(folder / "samples.h5", "r") as f:
            assert {f"E{k}" for k in range(20, 25)} <= set(f)
            assert f["E22"].attrs["rate_Hz"] == pytest.approx(4400 / 54)
    assert (out / "electrode_map.png").is_file()  # drawn on the SP's 24-electrode table


# --- --force over a sliding run's folder ---------------------------------------------------------------------------
def test_a_sliding_run_can_be_redone_into_its_folder_with_force(tmp_path):
    import json

    from bench.paths import FIXTURES
    from bench.reporting.outdir import RUN_FILES

    out = tmp_path / "foam"

    def run(*extra):
        return run_cli("run", FIXTURES / "scenes" / "foam.toml", "--out", out, "--quiet", *extra, timeout=300)

    r = run()
    assert r.returncode == 0, r.stderr
    written = {p.name for p in out.iterdir() if not p.name.startswith(".")}
    assert {"forces.png", "properties.png"} <= written and written <= set(RUN_FILES)
    r = run("--force")
    assert r.returncode == 0, r.stderr
    assert json.loads((out / "record.json").read_text())["status"] == "ok"


# --- scene sphere drops: Hertz impacts on the unit's own skin ------------------------------------------------------
def test_scene_sphere_drops_are_hertz_impacts_on_the_sensors_own_skin():
    from emulator.stimuli import MATERIAL_DENSITY_KG_PER_M3, SPHERE_RADII_M, SPHERES, hertz_contact, sphere_drop_on

    text = ('[scene]\nname = "d"\nduration_s = 1.0\n[sensor]\nskin_youngs_modulus_Pa = {E}\n'
            '[[stimulus]]\nkind = "sphere_drop"\nat_s = 0.2\nsphere = "1 mm steel bearing"\n'
            '[[stimulus]]\nkind = "sphere_drop"\nat_s = 0.4\nmass_mg = 4.089\ndiameter_mm = 2.0\n'
            '[[stimulus]]\nkind = "sphere_drop"\nat_s = 0.6\nmass_mg = 1.461\nmaterial = "aluminum"\n')
    base = parse_scene_text(text.replace("skin_youngs_modulus_Pa = {E}\n", ""))
    E = base.params.skin_youngs_modulus_Pa
    stiff = parse_scene_text(text.format(E=4 * E))
    for sc in (base, stiff):
        steel, wide, alu = sc.stimuli
        p = sc.params
        assert steel == sphere_drop_on(p, 0.2, SPHERES["1 mm steel bearing"][0], 0.07, sphere="1 mm steel bearing")
        assert steel.contact_s is None and steel.sphere_radius_m == SPHERE_RADII_M["1 mm steel bearing"]
        assert wide.sphere_radius_m == pytest.approx(1e-3) and wide.contact_s is None
        r_alu = (3 * 1.461e-6 / (4 * np.pi * MATERIAL_DENSITY_KG_PER_M3["aluminum"])) ** (1 / 3)
        assert alu.sphere_radius_m == pytest.approx(r_alu, rel=1e-12)
        modulus = p.skin_youngs_modulus_Pa / (1 - p.skin_poisson_ratio**2)
        for s in (steel, wide, alu):
            assert s.restitution == p.impact_restitution and s.contact_modulus_Pa == pytest.approx(modulus)
            assert s.contact_duration_s == hertz_contact(s.mass_kg, s.sphere_radius_m, s.impact_speed_m_per_s,
                                                         modulus)[0]
    # Hertz: t_c ∝ (m²/(R·E*²·v))^(1/5) -- a 4x stiffer skin shortens every impact by 4^(-2/5), a wider sphere of
    # the same mass shortens it by (R'/R)^(-1/5) and by (v'/v)^(-1/5) for the speed it lands at (slower: the air
    # holds a wider sphere back more)
    assert stiff.stimuli[0].contact_duration_s == pytest.approx(base.stimuli[0].contact_duration_s * 4 ** -0.4,
                                                                rel=1e-9)
    steel, wide = base.stimuli[:2]
    assert wide.impact_speed_m_per_s < steel.impact_speed_m_per_s
    assert wide.contact_duration_s == pytest.approx(
        steel.contact_duration_s * (wide.sphere_radius_m / steel.sphere_radius_m) ** -0.2
        * (wide.impact_speed_m_per_s / steel.impact_speed_m_per_s) ** -0.2, rel=1e-9)
    assert base.stimuli[0].contact_duration_s != pytest.approx(0.4e-3, rel=0.05)  # not the former fixed half-sine
