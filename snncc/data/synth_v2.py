"""Generator version 2 of the SYNTHETIC Braille set: calibrated to task difficulty (docs/braille_synthetic.md).

Same geometry as version 1 (``snncc.data.synth``: the iCub fingertip's 12 taxels, a six-dot cell
in the plate, dots as Gaussian bumps seen through Gaussian receptive fields), plus the sources of
difficulty a real recording has. Per repetition (trial) ``r``:

* **Contact force** ``F_r = exp(N(0, force_sigma))``; with probability ``p_no_contact`` the finger
  barely touches the plate (``F_r *= no_contact_force``).
* **Finger placement and dot alignment.** Start position along the slide ``N(0, start_sigma)`` mm,
  across it ``N(0, lateral_sigma)`` mm, yaw of the cell against the finger ``N(0, yaw_sigma)`` deg,
  and a pitch tilt that shifts the load along the finger: taxel gain
  ``exp((y_i - max y) / contact_length + tilt_r * (x_i - mean x))``, ``tilt_r ~ N(0, tilt_sigma)`` /mm.
* **Sliding speed and start time.** Speed ``20 exp(N(0, speed_sigma))`` mm/s over 15.5 mm, slide start
  ``t_start + N(0, onset_sigma)`` s.
* **Stick-slip of the fabric skin.** The skin sticks to the plate and slips in steps of
  ``U(slip_min, slip_max)`` mm of travel, so the dots' position in the finger frame is::

      s_eff(t) = (1 - a_r) s(t) + a_r * stair(s(t)),     a_r ~ U(stick_min, stick_max)

  ``stair`` holds the position of the last slip; after the slide the skin relaxes (``s_eff = s``).
  A step is faster than a frame (25 ms = 0.5 mm of travel), so a taxel can change by tens of counts
  between two frames: the source of sub-millisecond inter-event intervals and of the events lost
  to 5 ms binning. With probability ``p_slip`` the finger also slips sideways once during the slide
  by ``N(0, lateral_slip_mm)`` mm.
* **Taxel gain and saturation.** Per taxel (a sensor property, fixed per seed) gain
  ``exp(N(0, taxel_gain_sigma))`` and saturation ``saturation * exp(N(0, saturation_sigma))``; per
  trial a small gain jitter ``exp(N(0, trial_gain_sigma))``. Load = ``S_i (1 - exp(-p / S_i))``,
  times ``exp(j_ri N(0, 1))`` per frame and taxel, ``j_ri = load_jitter exp(N(0,
  load_jitter_level_sigma)) exp(N(0, load_jitter_taxel_sigma))`` (micro-slips of the loaded fabric:
  a fluctuation proportional to the load, so only pressed taxels flicker; its strength varies from
  trial to trial and, with how the fabric sits on each taxel, from taxel to taxel: a pressed taxel's
  events mark *when* it is loaded, while its event total varies independently of the letter).
* **Sensor.** Rest offset per taxel ``U(0, offset_max)`` + per-trial jitter, linear drift
  ``N(0, drift_sigma)`` counts/s, a slow AR(1) fluctuation (``wobble_sigma``, ``wobble_rho``: fabric
  creep, arm vibration) and white noise, both scaled per trial by ``exp(N(0, noise_level_sigma))``
  (a red + white spectrum whose level varies with the contact), then 8-bit quantisation
  ``raw = clip(round(255 - signal), 0, 255)``.

The defaults were tuned with ``bench/studies/calibrate_synth.py`` (see docs/braille_synthetic.md).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Callable

import numpy as np

from snncc.data.letters import CLASSES, FRAME_RATE_HZ, N_CLASSES
from snncc.data.fingertip import SLIDE_MM, SPEED_MM_S, TAXELS, dot_positions
from snncc.errors import SnnccError


@dataclass(frozen=True)
class SynthParamsV2:
    """Constants of the version-2 model (mm, s, deg, 8-bit counts). Defaults are the calibrated ones."""

    n_frames: int = 54
    frame_rate_hz: float = FRAME_RATE_HZ
    # geometry (as version 1)
    t_start: float = 0.2
    row_pitch: float = 4.0
    col_pitch: float = 5.0
    z_centre: float = 0.0
    x_first_row: float = -8.0
    dot_sigma: float = 0.6
    rf_sigma: float = 1.6
    contact_length: float = 12.0
    amplitude: float = 250.0
    saturation: float = 28.0
    # per-trial variation
    force_sigma: float = 0.25
    p_no_contact: float = 0.02
    no_contact_force: float = 0.1
    start_sigma: float = 0.6
    lateral_sigma: float = 0.5
    yaw_sigma: float = 4.0
    tilt_sigma: float = 0.04
    speed_sigma: float = 0.12
    onset_sigma: float = 0.1
    stick_min: float = 0.6
    stick_max: float = 0.9
    slip_min: float = 2.5
    slip_max: float = 5.0
    p_slip: float = 0.03
    lateral_slip_mm: float = 1.5
    # sensor
    taxel_gain_sigma: float = 0.2
    saturation_sigma: float = 0.1
    trial_gain_sigma: float = 0.1
    offset_max: float = 5.0
    offset_jitter: float = 0.5
    drift_sigma: float = 1.0
    noise_sigma: float = 0.05
    wobble_sigma: float = 0.1
    wobble_rho: float = 0.6
    noise_level_sigma: float = 0.2
    load_jitter: float = 0.055  # relative, per frame and taxel: micro-slips of the loaded fabric
    load_jitter_level_sigma: float = 0.4  # log-normal per trial factor on load_jitter
    load_jitter_taxel_sigma: float = 0.8  # log-normal per trial and taxel factor on load_jitter


DEFAULT_PARAMS_V2 = SynthParamsV2()


def _stair(s: np.ndarray, steps: np.ndarray) -> np.ndarray:
    """Position of the last completed slip: ``sum_k L_k * [c_k <= s]``, c = cumsum(L). s (r, T)."""
    c = np.cumsum(steps, axis=1)  # (r, K)
    done = s[:, :, None] >= c[:, None, :]  # (r, T, K)
    return np.einsum("rtk,rk->rt", done, steps)


def generate_v2(
    repetitions: int = 200,
    seed: int = 0,
    params: SynthParamsV2 = DEFAULT_PARAMS_V2,
    progress: Callable[[int], None] | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Raw 8-bit frames ``(27 * repetitions, n_frames, 12)`` uint8 (255 at rest) and labels.

    Samples are ordered letter by letter (Space, A, ..., Z); seeded (same arguments, same bytes).
    """
    if repetitions < 1:
        raise SnnccError(f"repetitions must be >= 1, got {repetitions}", field="repetitions")
    p = params
    rng = np.random.default_rng(seed)
    t = np.arange(p.n_frames) / p.frame_rate_hz  # (T,)
    tx, ty, tz = TAXELS[:, 0], TAXELS[:, 1], TAXELS[:, 2]
    two_var = 2.0 * (p.dot_sigma**2 + p.rf_sigma**2)
    # sensor properties, fixed for the whole set
    taxel_offset = rng.uniform(0.0, p.offset_max, size=12)
    taxel_gain = np.exp(rng.normal(0.0, p.taxel_gain_sigma, size=12))
    taxel_sat = p.saturation * np.exp(rng.normal(0.0, p.saturation_sigma, size=12))
    n_steps = int(np.ceil(SLIDE_MM / max(p.slip_min, 1e-3))) + 2
    frames = np.empty((N_CLASSES * repetitions, p.n_frames, 12), dtype=np.uint8)
    labels = np.repeat(np.arange(N_CLASSES, dtype=np.int64), repetitions)
    r = repetitions
    for label, letter in enumerate(CLASSES):
        dots = dot_positions(letter, p)  # (D, 2) at slide start, no jitter
        # placement: yaw about the cell centre, then shifts
        yaw = np.deg2rad(rng.normal(0.0, p.yaw_sigma, size=r))
        centre = np.array([p.x_first_row + p.row_pitch, p.z_centre])
        dx0 = rng.normal(0.0, p.start_sigma, size=r)
        dz0 = rng.normal(0.0, p.lateral_sigma, size=r)
        tilt = rng.normal(0.0, p.tilt_sigma, size=r)
        force = np.exp(rng.normal(0.0, p.force_sigma, size=r))
        force = np.where(rng.random(r) < p.p_no_contact, force * p.no_contact_force, force)
        trial_gain = np.exp(rng.normal(0.0, p.trial_gain_sigma, size=(r, 12)))
        # motion: speed, start time, stick-slip, occasional lateral slip
        speed = SPEED_MM_S * np.exp(rng.normal(0.0, p.speed_sigma, size=(r, 1)))
        onset = p.t_start + rng.normal(0.0, p.onset_sigma, size=(r, 1))
        s = np.clip(speed * (t[None, :] - onset), 0.0, SLIDE_MM)  # (r, T) nominal travel
        steps = rng.uniform(p.slip_min, p.slip_max, size=(r, n_steps))
        stick = rng.uniform(p.stick_min, p.stick_max, size=(r, 1))
        s_eff = (1.0 - stick) * s + stick * _stair(s, steps)
        s_eff = np.where(s >= SLIDE_MM, s, s_eff)
        slips = rng.random(r) < p.p_slip
        slip_at = rng.uniform(0.0, SLIDE_MM, size=(r, 1))
        slip_dz = np.where(slips, rng.normal(0.0, p.lateral_slip_mm, size=r), 0.0)
        dz_t = dz0[:, None] + slip_dz[:, None] * (s >= slip_at)  # (r, T)
        # sensor noise of this letter's trials
        level = np.exp(rng.normal(0.0, p.noise_level_sigma, size=(r, 1, 1)))
        offset = taxel_offset + rng.normal(0.0, p.offset_jitter, size=(r, 1, 12))
        drift = rng.normal(0.0, p.drift_sigma, size=(r, 1, 12)) * t[None, :, None]
        noise = level * rng.normal(0.0, p.noise_sigma, size=(r, p.n_frames, 12))
        innov = rng.normal(0.0, p.wobble_sigma * np.sqrt(1.0 - p.wobble_rho**2), size=(r, p.n_frames, 12))
        wobble = np.empty_like(innov)
        wobble[:, 0] = rng.normal(0.0, p.wobble_sigma, size=(r, 12))
        for n in range(1, p.n_frames):
            wobble[:, n] = p.wobble_rho * wobble[:, n - 1] + innov[:, n]
        wobble *= level
        pressure = np.zeros((r, p.n_frames, 12))
        cy, sy = np.cos(yaw), np.sin(yaw)
        for xd, zd in dots:
            ux, uz = xd - centre[0], zd - centre[1]
            xr = centre[0] + cy * ux - sy * uz + dx0  # (r,)
            zr = centre[1] + sy * ux + cy * uz
            xdt = xr[:, None] - s_eff  # (r, T) dot position in the finger frame
            zdt = zr[:, None] + dz_t
            d2 = (tx[None, None, :] - xdt[:, :, None]) ** 2 + (tz[None, None, :] - zdt[:, :, None]) ** 2
            pressure += np.exp(-d2 / two_var)
        gain = np.exp((ty - ty.max())[None, :] / p.contact_length + tilt[:, None] * (tx - tx.mean())[None, :])
        gain = gain * taxel_gain[None, :] * trial_gain  # (r, 12)
        pressure *= p.amplitude * (gain * force[:, None])[:, None, :]
        load = taxel_sat * (1.0 - np.exp(-pressure / taxel_sat))
        if p.load_jitter > 0:
            lj = p.load_jitter
            if p.load_jitter_level_sigma > 0:
                lj = lj * np.exp(rng.normal(0.0, p.load_jitter_level_sigma, size=(r, 1, 1)))
            if p.load_jitter_taxel_sigma > 0:
                lj = lj * np.exp(rng.normal(0.0, p.load_jitter_taxel_sigma, size=(r, 1, 12)))
            load *= np.exp(lj * rng.normal(0.0, 1.0, size=load.shape))
        signal = offset + drift + load + noise + wobble
        frames[label * r:(label + 1) * r] = np.clip(np.rint(255.0 - signal), 0, 255).astype(np.uint8)
        if progress is not None:
            progress((label + 1) * r)
    return frames, labels


def params_dict_v2(p: SynthParamsV2 = DEFAULT_PARAMS_V2) -> dict:
    return asdict(p)
