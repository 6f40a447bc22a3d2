"""Electrode claims: the pressed electrode's impedance rises with force (until the skin bottoms), pressing over an electrode moves it
most, a contact's change stays in the electrodes nearest it, the pattern points at the contact, and the same
contact's PDC rise (11.5 mN per bit).

Comparing electrodes.  A unit's electrodes rest under different fluid gaps (emulator.units), and the codes are far
from linear in the gap, so the same indentation moves a thin-gap electrode's code more than a thick-gap one's: raw
code changes compare the rests as much as the contact.  The claims that compare electrodes therefore compare each
electrode's change in fluid conductance G = 1/(Z − Z_series), Z from the codes by the published formula
(SENSOR.md §5, D eq. 4.1): with Z = Z_series + ρ/gap, ΔG·ρ is the change of the fluid's thickness over the
electrode — how far the skin moved there, whatever gap the electrode rested at.  To keep the claims' numbers and
bars in codes, each change is expressed as the code change of an electrode resting at the unit's median resting
conductance whose conductance changed by as much (:func:`common_rest_codes`).  When every electrode rests alike
(the nominal unit) that is the identity, so the nominal claims and their numbers are the raw-code ones.  A host
can do the same from the codes, knowing the electrodes' series impedance (and, for a bottomed skin, the minimum
gap over the sheet resistance).
"""

from __future__ import annotations

import numpy as np

from bench.verification.claims.core import Bench, Claim, claim_group
from emulator import conversions as conv
from emulator.electrodes import electrode_positions_mm, surface_point_mm
from emulator.sensor import NoiseSources
from emulator.stimuli import Touch

ELECTRODES = [f"E{n}" for n in range(1, 20)]
LOCAL_K = 4  # nearest electrodes (the pressed one included) whose share of the change is checked
LOCAL_SHARE = 0.70  # their share of Σ|Δcode| (common-rest): "most" (issue 10), with margin over the 62 % a
#                     uniform bulge gives
LOCATE_MM = 2.0  # median localisation error allowed: half the ~4 mm electrode spacing


def _codes_of_ohm(z_ohm):
    """Inverse of D eq. 4.1 (:func:`emulator.conversions.impedance_ohm`): the code of impedance Z, as a real."""
    return 4095.0 / (np.asarray(z_ohm, float) / 10e3 + 1.0)


def common_rest_codes(codes, rest_codes, p) -> np.ndarray:
    """Each electrode's code had it rested at the unit's median resting fluid conductance and its conductance changed
    by as much as it did (module docstring).  G = 1/(Z − Z_series) with Z from the codes by D eq. 4.1;
    G_equivalent = median(G_rest) + (G − G_rest), no lower than a bottomed skin's (minimum gap / sheet resistance).
    ``codes`` (..., N) and ``rest_codes`` (N,) of the electrodes; ``p`` the unit's parameters.  When every
    electrode rests alike (the nominal unit) this returns ``codes``."""
    zs = p.electrode_series_ohm
    z, z_rest = conv.impedance_ohm(codes), conv.impedance_ohm(rest_codes)
    if np.any(z <= zs) or np.any(z_rest <= zs):
        raise ValueError(f"an electrode code implies an impedance at or below the series impedance {zs:g} Ω "
                         f"(no fluid resistance left): codes up to {np.max(codes):g}, rest up to "
                         f"{np.max(rest_codes):g}")
    g, g_rest = 1.0 / (z - zs), 1.0 / (z_rest - zs)
    g_bottomed = p.minimum_gap_mm / p.fluid_sheet_ohm_mm
    g_equivalent = np.maximum(np.median(g_rest) + (g - g_rest), g_bottomed)
    return _codes_of_ohm(zs + 1.0 / g_equivalent)


def monotonic_until_bottomed(z_ohm, z_bottom_ohm: float, within: float = 0.02) -> bool:
    """True when the impedances ``z_ohm`` (Ω, by rising force) rise at every step, except a step between two
    readings that are both at the bottomed skin's impedance ``z_bottom_ohm`` (within the fraction ``within``); the
    first reading must not be bottomed (the lightest force leaves fluid to squeeze)."""
    z = np.asarray(z_ohm, float)
    bottomed = np.abs(z / z_bottom_ohm - 1.0) < within
    return bool(np.all((np.diff(z) > 0) | (bottomed[:-1] & bottomed[1:])) and not bottomed[0])


def contact_estimate_mm(changes, positions_mm, k: int = 4) -> np.ndarray:
    """Where a contact is (mm, as ``positions_mm``' rows): the centroid of the ``k`` electrodes whose ``changes``
    (codes, either sign) are largest in size, each weighted by the size of its change."""
    d = np.abs(np.asarray(changes, float))
    top = np.argsort(d)[-k:]
    return (d[top, None] * positions_mm[top]).sum(axis=0) / d[top].sum()


#: a touch's electrode codes are averaged from this long (s) before the instant asked for to the record's end, this
#: long (s) after it: inside the hold of the claims' touches (full force 0.1 s before the instant)
HELD_BEFORE_S, HELD_AFTER_S = 0.02, 0.05


def held_codes(b: Bench, touch, at_s: float) -> np.ndarray:
    """Each electrode's code (E1..E19, noise off) during ``touch``: the mean from :data:`HELD_BEFORE_S` before
    ``at_s`` (s) to :data:`HELD_AFTER_S` after it.  Each electrode is read twice in a row and the second reading
    kept: it has no memory of the previous electrode."""
    twice = [e for e in ELECTRODES for _ in range(2)]
    rec = b.acquire([touch], at_s + HELD_AFTER_S, sequence=twice, slot_rate_Hz=3800.0, noise=NoiseSources.none())
    out = []
    for e in ELECTRODES:
        t, code = rec[e]
        second = slice(1, None, 2)
        t, code = t[second], code[second]
        out.append(float(code[t >= at_s - HELD_BEFORE_S].astype(float).mean()))
    return np.array(out)


@claim_group("electrodes")
def electrode_claims(b: Bench) -> list[Claim]:
    """Monotonic impedance with force, the pressed electrode moves most, locality, localisation, PDC consistency."""

    def pattern(touch, at_s):
        return conv.impedance_ohm(held_codes(b, touch, at_s))

    rest_codes = held_codes(b, Touch(5.0, 1.0), 1.0)

    def change(touch, at_s):
        """Each electrode's change in common-rest codes (module docstring)."""
        return (common_rest_codes(held_codes(b, touch, at_s), rest_codes, b.params)
                - common_rest_codes(rest_codes, rest_codes, b.params))

    # monotonic rise of the pressed electrode's impedance with force
    forces = np.array([0.1, 0.3, 0.6, 1.0, 2.0, 3.5, 5.0])
    z17 = [float(pattern(Touch(0.2, float(f), 0.3, 1.0, electrode="E17", indenter_radius_mm=2.0), 0.6)[16])
           for f in forces]
    # ... until the skin bottoms on the core over it (a thin-gap electrode of a drawn unit bottoms under a few N):
    # from there the impedance stays at that of the minimum gap
    z_bottom = b.params.electrode_series_ohm + b.params.fluid_sheet_ohm_mm / b.params.minimum_gap_mm
    monotonic = monotonic_until_bottomed(z17, z_bottom)
    # pressing over each electrode moves that electrode most (its fluid thins most: common-rest code falls most)
    hits = 0
    for n in range(1, 20):
        dz = -change(Touch(0.2, 1.0, 0.3, 1.0, electrode=f"E{n}", indenter_radius_mm=1.5), 0.6)  # Z up: code down
        hits += int(np.argmax(dz) == n - 1)
    pos = electrode_positions_mm()
    dist = np.linalg.norm(pos[:, None, :] - pos[None, :, :], axis=2)
    # locality: a 1 N fingertip contact (3 mm indenter) over each electrode in turn; the share of the total
    # |Δcode| (common-rest) carried by the pressed electrode and its LOCAL_K − 1 nearest neighbours
    shares, far = [], []
    for n in range(1, 20):
        d = np.abs(change(Touch(0.2, 1.0, 0.3, 1.0, electrode=f"E{n}"), 0.6))
        nearest = np.argsort(dist[n - 1])[:LOCAL_K]
        shares.append(float(d[nearest].sum() / d.sum()))
        far.append(float(d[dist[n - 1] > 10.0].max()))
    share = float(np.median(shares))
    # localisation: 1 N contacts between electrodes; the |Δcode|-weighted (common-rest) centroid of the 4
    # electrodes that move most estimates the contact point
    errors = []
    for x_mm in (-11.0, -7.5, -4.0, -0.5, 2.0):
        for angle in (-50.0, -25.0, 0.0, 25.0, 50.0):
            estimate = contact_estimate_mm(change(Touch(0.2, 1.0, 0.3, 1.0, x_mm=x_mm, angle_deg=angle), 0.6), pos)
            errors.append(float(np.linalg.norm(estimate - surface_point_mm(x_mm, angle))))
    locate_mm = float(np.median(errors))
    # the same contact's DC pressure: 11.5 mN per PDC bit
    rec = b.acquire([Touch(0.5, 1.0, 0.3, 1.0, electrode="E17")], 1.5, sequence=("PDC",), slot_rate_Hz=200.0)
    t, pdc = rec["PDC"]
    rise = float(pdc[(t > 0.9) & (t < 1.7)].mean() - pdc[t < 0.45].mean())
    return [
        Claim("pressed electrode's impedance rises with force", "monotonic until the skin bottoms",
              float(monotonic), 1.0, 1.0, "monotonic", "D ch. 4; §5",
              {"force_N": forces.tolist(), "impedance_ohm": z17, "bottomed_ohm": z_bottom}, kind="consistency",
              note="the indentation depth is monotonic in force and Z = Z_series + ρ/gap by construction; where "
                   "the skin reaches the core the gap stops at its minimum"),
        Claim("pressing over an electrode moves it most", "19 of 19", float(hits), 19.0, 19.0, "electrodes",
              "§5 (electrode positions)", kind="consistency",
              note="the indentation is centred on the pressed electrode; checks positions and plumbing (changes "
                   "compared as fluid-thickness changes in common-rest codes: a unit's resting gaps differ)"),
        Claim(f"a 1 N contact's change stays in the nearest {LOCAL_K} electrodes",
              f"≥ {LOCAL_SHARE:.0%} of Σ|Δcode| (common-rest; median over E1..E19)", share, LOCAL_SHARE, 0.95,
              "of Σ|Δcode|",
              "realism requirement (on real units a contact changes mostly the electrodes near it); D ch. 4; "
              "electrode positions",
              {"share_per_electrode": shares, "k": LOCAL_K, "largest_change_beyond_10_mm_codes": far},
              kind="calibrated",
              calibration="bulge_width_ratio = 1/√2: the displaced liquid's rim bulge peaks at the indentation "
                          "width w, just outside the contact (a uniform bulge over the skin gives 62 %); the bar "
                          "is the review's 'most' with margin, not a measured figure",
              note=f"k = {LOCAL_K}: the pressed electrode and its 3 nearest neighbours (2.8–6.3 mm away), inside "
                   "the dimple-and-rim radius (~1.5 w ≈ 6 mm) of a 3 mm fingertip contact; Δcode of a nominal "
                   "electrode with the same fluid-thickness change (the raw Δcode for the nominal unit)"),
        Claim("a contact's electrode pattern locates it", f"median error < {LOCATE_MM:g} mm (half the ~4 mm "
              "spacing)", locate_mm, 0.0, LOCATE_MM, "mm",
              "Lin et al. 2013 (ICRA: point of contact estimated from the electrode impedances); G positions",
              {"errors_mm": errors}, kind="prediction",
              note="25 contacts between electrodes (x −11..2 mm, ±50°); |Δcode|-weighted centroid of the 4 "
                   "electrodes that move most (common-rest Δcode: the fluid-thickness change); nothing was "
                   "tuned to it (the bar is ours, not a published figure)"),
        Claim("a 1 N contact's PDC rise", "87 bits (11.5 mN/bit) ± 5 %", rise, 1.0 / 0.0115 * 0.95,
              1.0 / 0.0115 * 1.05, "bits", "D ch. 4; §1", kind="consistency",
              note="the force claims' 11.5 mN per PDC bit again, through a touch over an electrode"),
    ]
