"""The heated core, the thermistor and thermal contact with objects (SENSOR.md §4, D ch. 4).

A lumped thermal network, linear in its temperatures:

    heaters (4 resistors) -> core -> fluid -> skin -> ambient air
                              \\-> mount -> ambient     skin -> contact -> object layers -> object far field
    thermistor bead: between the core surface and the fluid, with its own heat capacity and self-heating

It settles ``heater_rise_K`` (10 K) above ambient and warms up over minutes after power-on.  An object in
contact is a stack of layers of geometrically growing thickness (1-D conduction into a half-space), so
metals, glass, stone, wood, plastics, foam and fabric draw heat according to their conductivity,
density and heat capacity (their effusivity), through a contact conductance.

Integration is exact for a linear system with inputs held over each step (matrix exponential), at the
network's own rate (100 Hz), in chunks aligned to absolute time: stable at any step, independent of how
callers slice time.  Outputs are interpolated to the instants asked for.

A contact decided while the run goes (a rig's commanded finger: ``ThermalContact.load_N``) touches while its load
is > 0, over the Hertz patch of that load; the network then advances step by step only through the first step at
or after the latest instant asked for, so it reads the load only at instants the sensor has already been asked
for (later commands may still change the rest).

Thermistor (NTC, the unit's own R25 and Beta: nominally 470 kΩ at 25 °C, B = 4025 K — the Beta model equivalent
to D eq. 4.4) in a divider with 30 kΩ from 10 V, buffered with a gain of 1.1 so that TDC/4095 = 100 kΩ/(R + 30 kΩ)
exactly as the published conversion assumes (whose constants are the nominal part's: a unit with another R25 or
Beta reads slightly off through it, as a real unit does), low-passed at 22.6 Hz -> TDC.  TAC = 1.65 V + 98 · HP(TDC), a first-order high-pass
at 0.45 Hz (Table 4-1; the text's 5 Hz is not used): for changes slower than 0.35 s, TAC − 1.65 V ≈
98·τ·dV_TDC/dt, which :func:`emulator.conversions.tac_to_celsius_per_s` inverts.  TDC and TAC swing between 0 V and
the 3.3 V supply rail (a shorted thermistor drives TDC there; a fast cold or hot contact at an extreme ambient, TAC).
"""

from __future__ import annotations

import functools
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numba import njit
from scipy import linalg

from emulator import filters
from emulator.effects import effect_rng
from emulator.params import SensorParams
from emulator.skin import contact_patch_radius_m

_NOMINAL = SensorParams()

THERMAL_RATE_HZ = 100.0
CHUNK_STEPS = 100  # the network advances in 1 s chunks aligned to absolute time
#: a live contact's patch radius is rounded to this step (at least one step while touching), so its load's many
#: values share a few discretizations of the network (model choice: 50 µm is the first object layer; the area of a
#: 1 N patch, radius 2.5 mm, is then within ±4 %)
PATCH_RADIUS_STEP_M = 50e-6


@dataclass(frozen=True)
class Material:
    """Thermal properties of an object: conductivity k (W/m/K), density ρ (kg/m³), specific heat c (J/kg/K)."""

    name: str
    k: float
    rho: float
    c: float

    @property
    def effusivity(self) -> float:
        """√(kρc), W·s^½/(m²·K): how strongly a touched surface draws heat."""
        return float(np.sqrt(self.k * self.rho * self.c))


#: Typical room-temperature values as tabulated in Incropera & DeWitt, *Fundamentals of Heat and Mass
#: Transfer* (6th ed.), Appendix A (Tables A.1 metals, A.2 nonmetallic solids, A.3 common materials).
MATERIALS: dict[str, Material] = {m.name: m for m in (
    Material("aluminum", 237.0, 2702.0, 903.0),
    Material("steel", 60.5, 7854.0, 434.0),
    Material("granite", 2.79, 2630.0, 775.0),
    Material("glass", 1.4, 2500.0, 750.0),
    Material("acrylic", 0.19, 1190.0, 1470.0),
    Material("wood", 0.12, 510.0, 1380.0),
    Material("cotton fabric", 0.06, 80.0, 1300.0),
    Material("polystyrene foam", 0.027, 55.0, 1210.0),
    # --- added for the texture library (fixtures/textures/library.toml) ---
    # Incropera & DeWitt Appendix A: A.1 (AISI 304), A.3 (paper; hardwoods oak/maple; balsa cross grain; cork
    # board; rubber, vulcanized soft; leather, sole).  Balsa's and leather's c are not tabulated there: balsa takes
    # the softwood entry's c, leather the usual 1.5 kJ/kg·K of tanned hide.
    Material("stainless steel", 14.9, 7900.0, 477.0),
    Material("paper", 0.180, 930.0, 1340.0),
    Material("hardwood", 0.16, 720.0, 1255.0),
    Material("balsa", 0.055, 140.0, 1380.0),
    Material("cork", 0.039, 120.0, 1800.0),
    Material("rubber (soft)", 0.13, 1100.0, 2010.0),
    Material("leather", 0.159, 998.0, 1500.0),
    # Callister, *Materials Science and Engineering*, Table 19.1 (c, k) and Appendix B (ρ): polymers.
    Material("PTFE", 0.25, 2200.0, 1050.0),
    Material("nylon", 0.24, 1140.0, 1670.0),
    Material("polyethylene", 0.48, 960.0, 1850.0),
    Material("polypropylene", 0.12, 905.0, 1925.0),
    Material("phenolic laminate", 0.15, 1300.0, 1650.0),
    # Handbook/data-sheet ranges where the textbooks above have no entry (mid-range values; k in W/m·K,
    # ρ in kg/m³, c in kJ/kg·K): flexible PVC k 0.14-0.17, ρ 1200-1350, c 1.0-1.4; filled silicone elastomer
    # k 0.2-0.3, ρ 1100-1200, c 1.2-1.5; isomolded graphite k 80-120, ρ 1750-1850, c 0.71; fired ceramic and
    # porcelain tile k 1.0-1.5, ρ 2000-2400, c 0.84.  Foams and fibre assemblies: Gibson & Ashby, *Cellular
    # Solids* (flexible PU foam ~30 kg/m³, EVA foam ~150 kg/m³), Morton & Hearle, *Physical Properties of
    # Textile Fibres* (wool c 1.36; pressed felt ~250 kg/m³), fur pelts k ~0.04 (Scholander et al. 1950).
    Material("vinyl (PVC)", 0.16, 1300.0, 1200.0),
    Material("silicone rubber", 0.20, 1150.0, 1300.0),
    Material("graphite", 100.0, 1780.0, 710.0),
    Material("ceramic tile", 1.3, 2300.0, 840.0),
    Material("polyurethane foam", 0.035, 30.0, 1400.0),
    Material("EVA foam", 0.05, 150.0, 2000.0),
    Material("wool felt", 0.05, 250.0, 1360.0),
    Material("fur", 0.04, 60.0, 1400.0),
)}


def material(name: str) -> Material:
    try:
        return MATERIALS[name]
    except KeyError:
        raise ValueError(f"unknown material {name!r}; known: {', '.join(MATERIALS)}") from None


# --- the thermistor and its read-out ---------------------------------------------------------------
# The thermistor is the unit's own part: R25 = ``p.thermistor_r25_ohm``, Beta = ``p.thermistor_beta_K`` (nominal
# 470 kΩ and 4025 K; emulator/units.py draws a unit's within the part's tolerance).  The published conversion
# (emulator/conversions.tdc_to_celsius, D eq. 4.4) keeps the nominal part's constants, so a unit whose thermistor
# differs reads a slightly wrong temperature through it, as a real unit does.
T25_K = 298.15
DIVIDER_OHM = 30e3
DIVIDER_SUPPLY_V = 10.0
TDC_BUFFER_GAIN = 1.1  # makes TDC/4095 = 100 kΩ/(R + 30 kΩ), the published conversion's divider
TAC_GAIN = 98.0
TAC_BIAS_V = 1.65


def thermistor_ohm(t_celsius, p: SensorParams | None = None):
    """Resistance (Ω) of the thermistor of unit ``p`` (None: the nominal unit) at ``t_celsius`` (Beta model:
    R = R∞·exp(B/T), R∞ = R25/exp(B/298.15 K))."""
    p = _NOMINAL if p is None else p
    r_inf = p.thermistor_r25_ohm / np.exp(p.thermistor_beta_K / T25_K)  # 470 kΩ, 4025 K -> R∞ ≈ 0.644 Ω
    return r_inf * np.exp(p.thermistor_beta_K / (np.asarray(t_celsius, float) + 273.15))


def tdc_volts(r_ohm, fault: str | None = None):
    """Buffered divider output for thermistor resistance ``r_ohm`` (open: R = ∞; short: R = 0)."""
    r = np.asarray(r_ohm, float)
    if fault == "open":
        r = np.full_like(r, np.inf)
    elif fault == "short":
        r = np.zeros_like(r)
    with np.errstate(divide="ignore", invalid="ignore"):
        v = TDC_BUFFER_GAIN * DIVIDER_SUPPLY_V * DIVIDER_OHM / (r + DIVIDER_OHM)
    if np.isfinite(v).all():  # (a new array: nan_to_num would only copy it)
        return v
    return np.nan_to_num(v, nan=0.0, posinf=0.0)


# --- the network ------------------------------------------------------------------------------------
CORE, FLUID, SKIN, BEAD = 0, 1, 2, 3
OBJECT_LAYERS = 10


def _object_layers(first_m: float = 50e-6, growth: float = 1.8) -> np.ndarray:
    return first_m * growth ** np.arange(OBJECT_LAYERS)


def live_patch_area_m2(load_N: np.ndarray, p: SensorParams) -> np.ndarray:
    """The skin's contact patch area (m²) under loads ``load_N`` (N, > 0) with the radius rounded to
    :data:`PATCH_RADIUS_STEP_M`, at least one step (:func:`emulator.skin.contact_patch_radius_m`)."""
    radius = contact_patch_radius_m(np.asarray(load_N, float), p.contact_radius_at_1N_m)
    steps = np.maximum(1.0, np.rint(radius / PATCH_RADIUS_STEP_M))
    return np.pi * (steps * PATCH_RADIUS_STEP_M) ** 2


@dataclass
class ThermalContact:
    """An object touching the skin over [start_s, end_s]: material, temperature (°C), contact area (m²).

    ``load_N``: for a contact decided while the run goes (a rig's commanded finger), the normal load (N) at
    instants (s, array), read only at instants already asked for; the object touches while it is > 0, over the
    patch of that load (:func:`live_patch_area_m2`), and ``area_m2`` is not used."""

    start_s: float
    end_s: float
    material: Material
    temperature_C: float
    area_m2: float = 0.0
    load_N: Callable[[np.ndarray], np.ndarray] | None = None

    @property
    def planned(self) -> bool:
        """Known in advance (False: decided while the run goes)."""
        return self.load_N is None


@dataclass
class ThermalEvents:
    """What changes the thermal network over time."""

    contacts: list[ThermalContact]
    power_on_s: float | None = None  # heater switched on at this instant, from ambient; None: settled since ever
    ambient_steps: tuple[tuple[float, float], ...] = ()  # (instant s, new ambient °C)
    heater_failed_s: float | None = None  # the heaters stop at this instant (the static fault: never ran)

    @property
    def any(self) -> bool:
        return bool(self.contacts or self.power_on_s is not None or self.ambient_steps or
                    self.heater_failed_s is not None)


class ThermalNetwork:
    """The network's matrices for a given contact (or none), and its exact discretization (remembered, up to
    :data:`CACHE_SIZE` of them; a pure function of the parameters, so copies and models share it)."""

    CACHE_SIZE = 1000

    def __init__(self, p: SensorParams):
        self.p = p
        self.layers = _object_layers()
        self.n = 4 + OBJECT_LAYERS
        self._cache: dict = {}
        self._steps_table = ({}, np.zeros((0, self.n, self.n)), np.zeros((0, self.n, 4)))

    def __deepcopy__(self, memo):
        return self

    def _remember(self, key, value):
        """Keep ``value`` under ``key`` (all is forgotten once :data:`CACHE_SIZE` are kept; a new dict, so a model
        in another thread never meets one half cleared); returns it."""
        if len(self._cache) >= self.CACHE_SIZE:
            self._cache = {}
        self._cache[key] = value
        return value

    def heater_power_W(self) -> float:
        """Heater power that holds the core ``heater_rise_K`` above ambient (steady state, no contact)."""
        key = ("heater",)
        if key not in (cache := self._cache):
            A, B = self.matrices(None)
            per_watt = np.linalg.solve(A, -B[:, 0])  # steady rise of every node per watt of heater (ambient 0)
            return self._remember(key, self.p.heater_rise_K / per_watt[CORE])
        return cache[key]

    def matrices(self, contact: tuple[Material, float] | None):
        """(A, B) of x' = A x + B u, x = [core, fluid, skin, bead, object layers] (°C),
        u = [heater W, ambient °C, object far field °C, bead self-heating W]."""
        key = _contact_key(contact)
        if key in (cache := self._cache):
            return cache[key]
        p = self.p
        n = self.n
        C = np.zeros(n)
        G = np.zeros((n, n))  # conductances between nodes
        g_amb = np.zeros(n)  # to ambient
        g_far = np.zeros(n)  # to the object's far field
        C[CORE], C[FLUID], C[SKIN], C[BEAD] = p.core_heat_capacity_J_per_K, p.fluid_heat_capacity_J_per_K, \
            p.skin_heat_capacity_J_per_K, p.thermistor_heat_capacity_J_per_K

        def link(i, j, g):
            G[i, j] += g
            G[j, i] += g

        link(CORE, FLUID, p.core_fluid_conductance_W_per_K)
        link(FLUID, SKIN, p.fluid_skin_conductance_W_per_K)
        link(BEAD, CORE, p.thermistor_conductance_W_per_K / 2)
        link(BEAD, FLUID, p.thermistor_conductance_W_per_K / 2)
        g_amb[SKIN] = p.skin_air_conductance_W_per_K
        g_amb[CORE] = p.mount_conductance_W_per_K
        obj = 4 + np.arange(OBJECT_LAYERS)
        if contact is None:
            C[obj] = 1.0  # detached layers relax to the far-field input (they are reset when an object is touched)
            g_far[obj] = 1.0
        else:
            mat, area = contact
            d = self.layers
            C[obj] = mat.rho * mat.c * area * d
            link(SKIN, obj[0], 1.0 / (1.0 / (p.contact_conductance_W_per_m2K * area) + d[0] / (2 * mat.k * area)))
            for i in range(OBJECT_LAYERS - 1):
                link(obj[i], obj[i + 1], mat.k * area / ((d[i] + d[i + 1]) / 2))
            g_far[obj[-1]] = mat.k * area / (d[-1] / 2)
        A = (G - np.diag(G.sum(axis=1) + g_amb + g_far)) / C[:, None]
        B = np.zeros((n, 4))
        B[CORE, 0] = 1.0 / C[CORE]
        B[:, 1] = g_amb / C
        B[:, 2] = g_far / C
        B[BEAD, 3] = 1.0 / C[BEAD]
        return self._remember(key, (A, B))

    def chunk_response(self, contact, dt: float, steps: int, live: bool = False):
        """(Φʲ, Σ_{i<j} Φⁱ Γ) for j = 1..steps: a whole chunk with inputs held is x_j = Φʲ x₀ + S_j u."""
        key = ("c", _contact_key(contact), dt, steps, live)
        if key not in (cache := self._cache):
            Phi, Gam = self.discrete(contact, dt, live)
            n = Phi.shape[0]
            powers = np.empty((steps, n, n))
            sums = np.empty((steps, n, Gam.shape[1]))
            P, S = np.eye(n), np.zeros_like(Gam)
            for j in range(steps):
                S = Phi @ S + Gam
                P = Phi @ P
                powers[j], sums[j] = P, S
            return self._remember(key, (powers, sums))
        return cache[key]

    def discrete(self, contact, dt: float, live: bool = False):
        """Exact zero-order-hold discretization (Φ, Γ) over ``dt`` (matrix exponential of the augmented system;
        ``live``: of a live contact's patch, by :func:`expm_products`)."""
        key = ("d", _contact_key(contact), dt, live)
        if key not in (cache := self._cache):
            A, B = self.matrices(contact)
            n, m = B.shape
            M = np.zeros((n + m, n + m))
            M[:n, :n], M[:n, n:] = A, B
            E = (expm_products if live else linalg.expm)(M * dt)
            return self._remember(key, (E[:n, :n], E[:n, n:]))
        return cache[key]

    def step_response(self, contact, dt: float, live: bool = False):
        """:meth:`discrete` with Φ made contiguous (for :func:`_steps`), remembered under the contact's exact area
        (m²): a live contact's repeated patches cost one look-up."""
        key = ("s", None if contact is None else (contact[0].name, contact[1]), dt, live)
        if key not in (cache := self._cache):
            Phi, Gam = self.discrete(contact, dt, live)
            return self._remember(key, (np.ascontiguousarray(Phi), Gam))
        return cache[key]


    def step_table(self, contacts: list, dt: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Φ and Γ of :meth:`step_response` stacked, and the row of each of ``contacts`` ((material, area m², live)
        or None: nothing touching) in them: one look-up per contact, no arrays built once its row exists (the
        stacks are replaced, never edited, as rows are added; forgotten past :data:`CACHE_SIZE` rows)."""
        keys = [None if c is None else (c[0].name, c[1], c[2]) for c in contacts]
        index, phis, gams = self._steps_table
        rows = [index.get((k, dt)) for k in keys]
        if None in rows:
            index = dict(index) if len(index) + len(keys) <= self.CACHE_SIZE else {}
            new = {}
            for c, k in zip(contacts, keys):
                if (k, dt) not in index and (k, dt) not in new:
                    new[(k, dt)] = self.step_response(None if c is None else c[:2], dt, c is not None and c[2])
            base = len(index) if index else 0
            phis, gams = (np.concatenate(([] if not index else [a]) + [np.stack([v[i] for v in new.values()])])
                          for i, a in enumerate((phis, gams)))
            index.update({key: base + r for r, key in enumerate(new)})
            self._steps_table = (index, phis, gams)
            rows = [index[(k, dt)] for k in keys]
        return phis, gams, np.array(rows)


def _contact_key(contact: tuple[Material, float] | None):
    """What a contact's matrices depend on: (material name, area m² to 1e-12 m²), or None."""
    return None if contact is None else (contact[0].name, round(contact[1], 12))


def expm_products(M: np.ndarray) -> np.ndarray:
    """exp(M) by scaling and squaring a degree-12 Taylor series (truncation < 1e-17 at the scaled norm ≤ 1/4):
    matrix products only.  A live contact meets dozens of patch areas per trial; scipy's expm runs through a second
    BLAS whose threads, woken for each call, can cost milliseconds on a busy machine."""
    norm = float(np.abs(M).sum(axis=0).max())
    squarings = max(0, int(np.ceil(np.log2(norm / 0.25)))) if norm > 0 else 0
    X = M / 2.0**squarings
    term = E = np.eye(M.shape[0])
    for k in range(1, 13):
        term = term @ X / k
        E = E + term
    for _ in range(squarings):
        E = E @ E
    return E


@njit(cache=True)
def _steps(Phi: np.ndarray, x: np.ndarray, gu: np.ndarray, out: np.ndarray) -> np.ndarray:
    """x ← Φ x + Γu once per row of ``out``, each state written to its row; returns the last.  The same numbers as
    numpy's ``Phi @ x + gu`` step by step (np.dot calls the same BLAS matrix-vector product; tested), without a
    Python round trip per step."""
    for i in range(out.shape[0]):
        x = np.dot(Phi, x) + gu
        out[i] = x
    return x


@njit(cache=True)
def _step_runs(phis: np.ndarray, gams: np.ndarray, rows: np.ndarray, bounds: np.ndarray, heater: np.ndarray,
               ambient: np.ndarray, index: np.ndarray, temperature: np.ndarray, p_self: float, previous: int,
               x: np.ndarray, out: np.ndarray) -> np.ndarray:
    """Run r: rows j = ``bounds[r]``..``bounds[r + 1]`` of ``out`` by :func:`_steps` with Φ = ``phis[rows[r]]`` and
    Γu = ``gams[rows[r]]`` · u (numpy's matrix-vector product, the same BLAS call), u = [``heater[j]`` W,
    ``ambient[j]`` °C, far field: the touched contact's ``temperature`` (°C, contact ``index[j]``) or the ambient,
    ``p_self`` W] (:meth:`ThermalModel._u`), from the state the run before left (first: ``x``); a newly touched
    object (its index not the run before's, first: ``previous``; -1: none) arrives at its temperature first.
    Returns the last state."""
    u = np.empty(4)
    for r in range(bounds.size - 1):
        j = bounds[r]
        i = index[j]
        if i >= 0 and i != previous:
            x = x.copy()
            x[4:] = temperature[i]
        previous = i
        u[0], u[1], u[3] = heater[j], ambient[j], p_self
        u[2] = temperature[i] if i >= 0 else ambient[j]
        x = _steps(phis[rows[r]], x, np.dot(gams[rows[r]], u), out[j:bounds[r + 1]])
    return x


def output_rails(v, p: SensorParams):
    """``v`` (V) limited to the amplifiers' output swing, 0 V to the supply rail of ``p`` (TDC's buffer, TAC's
    amplifier)."""
    return np.clip(v, 0.0, p.supply_rail_V)


@functools.lru_cache(maxsize=16)
def shared_network(p: SensorParams) -> ThermalNetwork:
    """The network of parameters ``p``, shared by every model built with them (its discretizations are computed
    once: a rig's live contact meets dozens of patch areas in each trial)."""
    return ThermalNetwork(p)


class ThermalModel:
    """Advances the network and serves core temperature, TDC and TAC voltages at any instants (s)."""

    def __init__(self, p: SensorParams, events: ThermalEvents, seed: int, faults: dict | None = None,
                 tac_discretization: str = "prewarped", noise: bool = True):
        self.p = p
        self.events = events
        self.faults = faults or {}
        self.net = shared_network(p)
        self.dt = 1.0 / THERMAL_RATE_HZ
        self.heater_W = self.net.heater_power_W()
        self.rng = effect_rng(seed, "thermistor_noise")
        self.noise_V = p.tdc_noise_V if noise else 0.0
        # state at step k0: start settled (heater on since ever) or at ambient (power-on scene)
        self.k = 0
        self._touching = None
        self.x = self._initial_state()
        # a live contact (decided while the run goes): advance step by step, no further than asked for
        self.live = not all(c.planned for c in events.contacts)
        self._p_self = 0.0  # bead self-heating (W) of the current chunk
        self._last_touch = None  # (contact index, area m²) of the last step, or None
        self._held = None  # (first step, inputs, x, u) of a chunk's closed form while its inputs stay those then
        self._contact_temperatures = None  # (see _temperatures)
        # read-out filters run at the network rate: 22.6 Hz low-pass on TDC, 0.45 Hz high-pass x 98 on TAC
        fs = THERMAL_RATE_HZ
        z, pz, k = np.array([]), np.array([-2 * np.pi * p.tdc_bandwidth_Hz]), 2 * np.pi * p.tdc_bandwidth_Hz
        self.tdc_filter = filters.SosFilter(filters.discretize(z, pz, k, fs, tac_discretization))
        zh, ph, kh = filters.highpass_1st(p.tac_highpass_Hz)
        self.tac_filter = filters.SosFilter(filters.discretize(zh, ph, kh, fs, tac_discretization, gain_at_hz=10.0))
        v0 = float(self._tdc_from_state(self.x[None, :])[0])
        self.tdc_filter.settle(v0)
        tdc0 = float(self._rails(v0))  # the buffer's output
        self.tac_filter.settle(tdc0)
        self._hist_t = np.zeros(0)
        self._hist = np.zeros((0, 3))  # core °C, TDC V, TAC V at step instants
        self._pending: list = []  # chunks not yet merged into the history
        self._append(self.k, self.x[None, :], np.array([tdc0]), np.array([float(self._rails(TAC_BIAS_V))]))

    def _rails(self, v):
        """``v`` (V) limited to the amplifiers' output swing (:func:`output_rails`)."""
        return output_rails(v, self.p)

    # --- inputs ------------------------------------------------------------------------------
    def inputs_at(self, times: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Heater power (W) and ambient temperature (°C) at each instant (s) of ``times``: the one rule for both
        (no heater before power-on, from a heater failure on, or with the ``heater_failed`` fault; ambient steps take
        effect at their instant)."""
        times = np.asarray(times, float)
        e = self.events
        heater = np.full(times.size, self.heater_W)
        if self.faults.get("heater_failed"):
            heater[:] = 0.0
        if e.heater_failed_s is not None:
            heater[times >= e.heater_failed_s] = 0.0
        if e.power_on_s is not None:
            heater[times < e.power_on_s] = 0.0
        ambient = np.full(times.size, self.p.ambient_temperature_C)
        for when, value in e.ambient_steps:
            ambient[times >= when] = value
        return heater, ambient

    def _event_times(self, t0: float, t1: float) -> list[float]:
        """Instants in [t0, t1] where an input may change (plus t1), to test whether a chunk is uniform."""
        e = self.events
        times = [t1]
        for c in e.contacts:
            times += [c.start_s, c.end_s]
        times += [w for w, _ in e.ambient_steps]
        times += [v for v in (e.power_on_s, e.heater_failed_s) if v is not None]
        return [t for t in times if t0 <= t <= t1]

    def contact_at(self, t: float):
        """The first planned contact touching at ``t`` (s), or None."""
        for c in self.events.contacts:
            if c.start_s <= t < c.end_s:
                return c
        return None

    def touches(self, times: np.ndarray) -> list:
        """Per instant (s): (contact index, area m²) of the first contact touching then, or None; a live contact
        reads its load at these instants only."""
        index, area = self._touch_arrays(times)
        return [None if i < 0 else (i, a) for i, a in zip(index.tolist(), area.tolist())]

    def _touch_arrays(self, times: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`touches` as arrays: per instant (s) the first touching contact's index (-1: none) and area (m²,
        0 where none)."""
        index = np.full(times.size, -1)
        area = np.zeros(times.size)
        for i, c in enumerate(self.events.contacts):
            on = (times >= c.start_s) & (times < c.end_s)
            if not on.any():
                continue
            if c.planned:
                a = c.area_m2
            else:
                load = c.load_N(times[on])
                on[on] = load > 0
                a = live_patch_area_m2(load[load > 0], self.p)
            first = on & (index < 0)
            area[first] = a if c.planned else a[first[on]]
            index[first] = i
        return index, area

    @staticmethod
    def _u(heater_W: float, ambient_C: float, contact: ThermalContact | None, p_self: float) -> np.ndarray:
        """u = [heater W, ambient °C, object far field °C, bead self-heating W] with ``contact`` touching (None:
        nothing; the far field is then at ambient)."""
        return np.array([heater_W, ambient_C, contact.temperature_C if contact else ambient_C, p_self])

    def _initial_state(self) -> np.ndarray:
        heater, ambient = (float(v[0]) for v in self.inputs_at(np.zeros(1)))
        if self.events.power_on_s is not None:
            heater = 0.0
        return _settled_state(self.p, heater, ambient).copy()

    # --- outputs --------------------------------------------------------------------------------
    def _tdc_from_state(self, xs: np.ndarray) -> np.ndarray:
        return tdc_volts(thermistor_ohm(xs[:, BEAD], self.p), self.faults.get("thermistor"))

    def _self_heating_W(self, bead_C: float) -> float:
        return _self_heating_W(self.p, bead_C)

    def _append(self, k0, xs, tdc, tac):
        t = (k0 + np.arange(len(xs))) * self.dt
        self._pending.append((t, np.column_stack([xs[:, CORE], tdc, tac])))
        self._last_t = t[-1]

    def _history(self):
        if self._pending:
            self._hist_t = np.concatenate([self._hist_t, *(t for t, _ in self._pending)])
            self._hist = np.vstack([self._hist, *(v for _, v in self._pending)])
            self._pending = []
        return self._hist_t, self._hist

    def _arrive(self, x: np.ndarray, contact: ThermalContact | None) -> np.ndarray:
        """State ``x`` as ``contact`` touches (None: nothing): a newly touched object arrives at its own temperature."""
        if contact is not None and contact is not self._touching:
            x = x.copy()
            x[4:] = contact.temperature_C
        self._touching = contact
        return x

    def _response(self, contact: ThermalContact | None, area_m2: float | None, steps: int | None = None):
        """The network's (Φ, Γ) over one step with ``contact`` touching over ``area_m2`` (None: nothing), or
        with ``steps`` its :meth:`ThermalNetwork.chunk_response`."""
        touching = None if contact is None else (contact.material, area_m2)
        live = contact is not None and not contact.planned
        if steps is None:
            return self.net.discrete(touching, self.dt, live)
        return self.net.chunk_response(touching, self.dt, steps, live)

    def _emit(self, k_first: int, xs: np.ndarray) -> None:
        """Read out states ``xs`` of steps ``k_first``, ``k_first`` + 1, …: thermistor noise, TDC and TAC filters."""
        v = self._tdc_from_state(xs)
        if self.noise_V:
            v = v + self.noise_V * self.rng.standard_normal(v.shape)
        # TDC's buffer and TAC's amplifier swing between the supply rails, as the pressure front end's: a shorted
        # thermistor (11 V from the 10 V divider) or a low-R25 part drives TDC there, a fast enough TDC swing (cold
        # aluminium at a hot ambient) TAC
        tdc = self._rails(self.tdc_filter(v))
        tac = self._rails(TAC_BIAS_V + TAC_GAIN * self.tac_filter(tdc))
        self._append(k_first, xs, tdc, tac)

    def _advance_chunk(self) -> None:
        """Advance one chunk of CHUNK_STEPS steps (inputs held per step; contact and events at step starts)."""
        k0 = self.k
        xs = np.empty((CHUNK_STEPS, self.net.n))
        x = self.x
        p_self = self._self_heating_W(float(x[BEAD]))  # updated once per chunk: it changes slowly
        t0, t1 = k0 * self.dt, (k0 + CHUNK_STEPS - 1) * self.dt
        c0 = self.contact_at(t0)
        checks = [t0] + self._event_times(t0, t1)  # the instants where an input may change
        heater, ambient = self.inputs_at(np.array(checks))
        steady = bool((heater == heater[0]).all() and (ambient == ambient[0]).all()) and \
            all(self.contact_at(t) == c0 for t in checks) and (c0 is None or c0 is self._touching)
        if steady:  # inputs held over the whole chunk: closed form, one matrix product
            powers, sums = self._response(c0, None if c0 is None else c0.area_m2, CHUNK_STEPS)
            xs = powers @ x + sums @ self._u(heater[0], ambient[0], c0, p_self)
            x = xs[-1]
        else:
            times = (k0 + np.arange(CHUNK_STEPS)) * self.dt
            heater, ambient = self.inputs_at(times)
            for j, t in enumerate(times.tolist()):
                c = self.contact_at(t)
                x = self._arrive(x, c)
                Phi, Gam = self._response(c, None if c is None else c.area_m2)
                x = Phi @ x + Gam @ self._u(heater[j], ambient[j], c, p_self)
                xs[j] = x
        self.x = x
        self.k = k0 + CHUNK_STEPS
        self._emit(k0 + 1, xs)

    def _advance_live(self, k_end: int) -> None:
        """Advance step by step through step ``k_end`` and not beyond (a live contact: its load is read only at
        the steps' starts, all before ``k_end``·dt).  Independent of how time is cut: the self-heating is updated
        at chunk boundaries (absolute time) and a chunk that starts with the previous step's contact runs in
        closed form from its start for as long as its inputs stay those at its start, stepwise after.  Steps are
        taken in runs of equal inputs within a chunk: a run in closed form is one slice of the chunk's states; the
        runs stepwise of a chunk are one compiled pass (:func:`_step_runs`), each run repeating its one step's
        (Φ, Γu)."""
        k0 = self.k
        times = (k0 + np.arange(k_end - k0)) * self.dt
        index, area = self._touch_arrays(times)
        heater, ambient = self.inputs_at(times)
        # runs: a step starts one where its inputs differ from the previous step's or a chunk starts
        starts = np.ones(times.size, bool)
        starts[1:] = (heater[1:] != heater[:-1]) | (ambient[1:] != ambient[:-1]) | (index[1:] != index[:-1]) | \
            (area[1:] != area[:-1])
        chunk_starts = (k0 + np.arange(times.size)) % CHUNK_STEPS == 0
        starts[chunk_starts] = True
        bounds = np.flatnonzero(starts).tolist() + [times.size]
        segments = np.flatnonzero(chunk_starts).tolist()
        segments = ([0] if not segments or segments[0] else []) + segments + [times.size]
        arrays = heater, ambient, index, area
        bound_array = np.array(bounds)
        heater, ambient, index, area = (v.tolist() for v in arrays)
        contacts = self.events.contacts
        xs = np.empty((times.size, self.net.n))
        x = self.x
        b = 0  # bounds[b]: the next run's first step
        for j, seg_end in zip(segments[:-1], segments[1:]):
            k = k0 + j
            touch = None if index[j] < 0 else (index[j], area[j])
            here = (heater[j], ambient[j], touch)
            contact = None if touch is None else contacts[touch[0]]
            if k % CHUNK_STEPS == 0:
                self._p_self = self._self_heating_W(float(x[BEAD]))  # updated once per chunk, as for planned
                self._held = None
                if touch == self._last_touch:
                    self._held = (k, here, x, self._u(heater[j], ambient[j], contact, self._p_self))
            run_end = bounds[b + 1]
            if self._held is not None and self._held[1] == here:  # the segment's first run, in closed form
                k_held, _, x_held, u_held = self._held
                powers, sums = self._response(contact, None if touch is None else touch[1], CHUNK_STEPS)
                rows = slice(k - k_held, k - k_held + run_end - j)  # only the chunk's states used
                xs[j:run_end] = powers[rows] @ x_held + sums[rows] @ u_held
                x = xs[run_end - 1]
                self._last_touch = touch
                b += 1
            if bounds[b] < seg_end:  # the rest of the segment stepwise, one compiled pass over its runs
                self._held = None
                b_end = bounds.index(seg_end, b)
                x = self._step_runs(x, bound_array[b:b_end + 1], *arrays, xs)
                b = b_end
        self.x = x
        self.k = k_end
        self._emit(k0 + 1, xs)

    def _step_runs(self, x: np.ndarray, bounds: np.ndarray, heater: np.ndarray, ambient: np.ndarray,
                   index: np.ndarray, area: np.ndarray, out: np.ndarray) -> np.ndarray:
        """Take the runs of steps ``bounds[r]``..``bounds[r + 1]`` (rows of ``out``) stepwise from state ``x``, each
        with its first step's inputs (``heater`` W, ``ambient`` °C, contact ``index`` or -1, ``area`` m², per row),
        writing each state to ``out``; returns the last.  A newly touched object arrives at its temperature
        (:meth:`_arrive`)."""
        contacts = self.events.contacts
        first = bounds[:-1]
        runs = list(zip(index[first].tolist(), area[first].tolist()))
        touching = [None if i < 0 else (contacts[i].material, a, not contacts[i].planned) for i, a in runs]
        phis, gams, rows = self.net.step_table(touching, self.dt)
        previous = -1 if self._touching is None else next(k for k, c in enumerate(contacts) if c is self._touching)
        i, a = runs[-1]
        self._touching = None if i < 0 else contacts[i]
        self._last_touch = None if i < 0 else (i, a)
        return _step_runs(phis, gams, rows, bounds, heater, ambient, index, self._temperatures(), self._p_self,
                          previous, x, out)

    def _temperatures(self) -> np.ndarray:
        """Each contact's object temperature (°C), by contact index."""
        if self._contact_temperatures is None:
            self._contact_temperatures = np.array([c.temperature_C for c in self.events.contacts], dtype=float)
        return self._contact_temperatures

    def values_at(self, times: np.ndarray) -> np.ndarray:
        """(core °C, TDC V, TAC V) at each instant, linearly interpolated between network steps."""
        times = np.asarray(times, float)
        if times.size == 0:
            return np.zeros((0, 3))
        ht, hv = self._history_through(times)
        return np.column_stack([np.interp(times, ht, hv[:, i]) for i in range(3)])

    def value_at(self, times: np.ndarray, column: int) -> np.ndarray:
        """One of :meth:`values_at`'s columns (0 core °C, 1 TDC V, 2 TAC V) at each instant: the same values,
        without interpolating the other two."""
        times = np.asarray(times, float)
        if times.size == 0:
            return np.zeros(0)
        ht, hv = self._history_through(times)
        return np.interp(times, ht, hv[:, column])

    def _history_through(self, times: np.ndarray):
        """The history (step instants s, values), advanced through the latest of ``times`` (s, not empty)."""
        t_max = times.max()
        while self._last_t < t_max:
            if self.live:  # through the first step at or after the latest instant asked for, not beyond
                self._advance_live(max(self.k + 1, int(np.ceil(t_max / self.dt - 1e-9))))
            else:
                self._advance_chunk()
        ht, hv = self._history()
        if times.min() < ht[0]:
            raise ValueError(f"instant {times.min():.6f} s is older than the thermal history")
        return ht, hv

    def forget_before(self, t: float) -> None:
        """Drop history before ``t`` (s): no instant before it will be asked for again."""
        self._history()
        keep_from = np.searchsorted(self._hist_t, t, side="right") - 1
        if keep_from > 0:
            self._hist_t, self._hist = self._hist_t[keep_from:], self._hist[keep_from:]


@functools.lru_cache(maxsize=64)
def _settled_state(p: SensorParams, heater_W: float, ambient_C: float) -> np.ndarray:
    """:func:`settled_state` of the network and thermistor of parameters ``p`` (remembered: every rig trial starts
    settled; callers copy it)."""
    return settled_state(shared_network(p), heater_W, ambient_C, functools.partial(_self_heating_W, p))


def _self_heating_W(p: SensorParams, bead_C: float) -> float:
    """The thermistor's self-heating (W) at bead temperature ``bead_C`` (°C): V²/R across it in the divider."""
    r = float(thermistor_ohm(bead_C, p))
    v = DIVIDER_SUPPLY_V * r / (r + DIVIDER_OHM)
    return v * v / r


def settled_state(net: ThermalNetwork, heater_W: float, ambient_C: float, self_heating) -> np.ndarray:
    """Steady state of the network with no contact, the thermistor's self-heating included."""
    A, B = net.matrices(None)
    p_self = 0.0
    for _ in range(3):  # self-heating depends (weakly) on the bead temperature it causes
        x = np.linalg.solve(A, -B @ np.array([heater_W, ambient_C, ambient_C, p_self]))
        p_self = self_heating(float(x[BEAD]))
    x[4:] = ambient_C
    return x


def steady_state(p: SensorParams, faults: dict | None = None) -> tuple[float, float, float]:
    """(core °C, TDC V, TAC V) of the settled sensor at rest: the shortcut when nothing thermal happens."""
    faults = faults or {}
    return _steady_state(p, faults.get("thermistor"), bool(faults.get("heater_failed")))


@functools.lru_cache(maxsize=64)
def _steady_state(p: SensorParams, thermistor_fault, heater_failed: bool) -> tuple[float, float, float]:
    """:func:`steady_state` for the only faults it depends on (remembered: sensors built one after another share
    it)."""
    # (the settled state a thermal network with no events starts from, without building one: 0.2 -> 0.08 ms)
    heater = 0.0 if heater_failed else shared_network(p).heater_power_W()
    x = _settled_state(p, heater, p.ambient_temperature_C)
    tdc = float(tdc_volts(thermistor_ohm(x[BEAD], p), thermistor_fault))
    return float(x[CORE]), float(output_rails(tdc, p)), float(output_rails(TAC_BIAS_V, p))
