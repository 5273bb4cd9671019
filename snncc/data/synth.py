"""A calibrated physical model of the tactile Braille recording (SYNTHETIC data, not the real set).

This module holds generator version 1 and the version switch (:func:`generate`, default
:data:`GENERATOR_VERSION` = 2, see ``snncc.data.synth_v2``); the geometry both versions share is
``snncc.data.fingertip``. Version 1:

The real Zenodo recordings cannot be fetched on these machines, so ``snncc data synth`` builds a
stand-in from the recording's physics (docs/braille.md: the recording; docs/braille_synthetic.md: the model):

* **Geometry.** The iCub fingertip's 12 taxel centres (``TAXELS``, mm; x along the finger, y the
  pad normal, z across). The letter lies in the plate; its six-dot cell has its columns across
  the finger (z = ``z_centre -+ col_pitch/2``) and its rows along the slide (``row_pitch`` apart).
* **Dots as bumps, fabric as receptive fields.** A dot presses the skin with a Gaussian bump of
  width ``dot_sigma``; the three-layer fabric spreads it further, so each taxel integrates the
  pressure over a Gaussian receptive field of width ``rf_sigma`` that overlaps its neighbours. The
  convolution of two Gaussians is a Gaussian, so a dot at (xd, zd) gives taxel i::

      p_i = A * g_i * exp(-((x_i - xd)^2 + (z_i - zd)^2) / (2 * (dot_sigma^2 + rf_sigma^2)))

  with ``g_i = exp((y_i - max y) / contact_length)``: taxels further from the plate are pressed
  less.  Pressures of all dots add and saturate like a capacitor plate, ``P (1 - exp(-p / P))``.
* **Motion.** The finger rests for ``t_start`` s, slides 15.5 mm at 20 mm/s, then rests until the
  end of the 54 frames (1.35 s) at 40 Hz. Per repetition: Gaussian start position along the slide
  (``start_sigma`` mm) and across it (``lateral_sigma``), Gaussian start time of the slide
  (``onset_sigma`` s), log-normal contact force (``force_sigma``); ``slip_sigma`` (fabric
  stick-slip) exists but is off: it destroyed the time-collapsed accuracy during calibration.
* **Sensor.** A fixed rest offset per taxel (``offset_max``) with a small per-repetition jitter, a
  linear drift, a slow AR(1) contact fluctuation (``wobble_sigma``, ``wobble_rho``), white noise
  per frame, and 8-bit quantisation of the capacitance counts:
  ``raw = clip(round(255 - signal), 0, 255)`` (255 at rest, 0 at full load, as the device reports
  before the software inversion).

Calibration: the constants were tuned by a hand-guided search so that the paper's own analyses,
run by ``snncc data analyse`` on the default set (27 letters x 200 repetitions, seed 0), give the
paper's numbers. Measured: linear SVM one-vs-rest, 5-fold CV, 87.5 % on raw frames (paper 86.7)
and 71.4 % time-collapsed (72.3); mean events per taxel and sample 94.7 / 37.3 / 9.5 / 3.8 at
thresholds 1 / 2 / 5 / 10 (87.6 / 38.0 / 10.5 / 3.4). See ``docs/braille_synthetic.md``. Anything
else (binning losses, inter-spike intervals, SVMs on binned events) is *not* calibrated and
differs from the real recordings.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Callable

import numpy as np

from snncc.data.fingertip import SLIDE_MM, SPEED_MM_S, TAXELS, dot_positions  # noqa: F401  (re-exported)
from snncc.data.letters import CLASSES, FRAME_RATE_HZ, N_CLASSES
from snncc.errors import SnnccError



@dataclass(frozen=True)
class SynthParams:
    """Constants of the physical model (mm, s, 8-bit counts). Defaults are the calibrated ones."""

    n_frames: int = 54
    frame_rate_hz: float = FRAME_RATE_HZ
    t_start: float = 0.2  # s at rest before the slide starts
    row_pitch: float = 4.0  # mm between Braille rows (along the slide)
    col_pitch: float = 5.0  # mm between the two columns (across the finger)
    z_centre: float = 0.0  # mm, lateral centre of the cell
    x_first_row: float = -8.0  # mm, first row's position (finger frame) at slide start
    dot_sigma: float = 0.6  # mm, Gaussian width of a dot's indentation
    rf_sigma: float = 1.6  # mm, Gaussian receptive field of a taxel through the fabric
    contact_length: float = 3.0  # mm, pressure falls as exp((y - 4.4) / contact_length)
    amplitude: float = 130.0  # counts for one dot centred on the most exposed taxel
    saturation: float = 60.0  # counts, saturation of the capacitance
    start_sigma: float = 1.5  # mm, Gaussian jitter of the start position along the slide
    onset_sigma: float = 0.1  # s, jitter of the slide's start time within the recording
    slip_sigma: float = 0.0  # log-normal factor on the skin's travel over the letter (stick-slip of the fabric)
    lateral_sigma: float = 0.2  # mm, Gaussian jitter across the finger
    force_sigma: float = 0.07  # log-normal contact force variation per repetition
    offset_max: float = 5.0  # counts, rest offset of each taxel (a sensor property), U(0, offset_max)
    offset_jitter: float = 0.5  # counts, its variation from repetition to repetition (Gaussian)
    drift_sigma: float = 0.5  # counts/s, linear drift per taxel and repetition
    noise_sigma: float = 0.6  # counts, white sensor noise per frame
    wobble_sigma: float = 1.5  # counts, slow (AR(1)) fluctuation of the contact: fabric creep, vibration
    wobble_rho: float = 0.5  # AR(1) coefficient per frame of that fluctuation


DEFAULT_PARAMS = SynthParams()


def slide_offset(t: np.ndarray, t_start: float | np.ndarray) -> np.ndarray:
    """Finger displacement (mm) at times ``t``: rest until ``t_start``, 20 mm/s for 15.5 mm, rest."""
    return SPEED_MM_S * np.clip(t - t_start, 0.0, SLIDE_MM / SPEED_MM_S)


GENERATOR_VERSION = 2  # the default; version 1 stays reachable with version=1 / --generator-version 1
VERSIONS = (1, 2)


def _check_version(version: int) -> int:
    if int(version) not in VERSIONS:
        raise SnnccError(f"generator version must be one of {', '.join(map(str, VERSIONS))}, got {version}",
                         field="generator_version")
    return int(version)


def default_params(version: int = GENERATOR_VERSION):
    """The calibrated constants of a generator version (``SynthParams`` or ``SynthParamsV2``)."""
    if _check_version(version) == 1:
        return DEFAULT_PARAMS
    from snncc.data.synth_v2 import DEFAULT_PARAMS_V2

    return DEFAULT_PARAMS_V2


def generate(
    repetitions: int = 200,
    seed: int = 0,
    params=None,
    progress: Callable[[int], None] | None = None,
    version: int | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Raw frames and labels from generator ``version`` (2: calibrated to task difficulty;
    1: calibrated to summary statistics only; docs/braille_synthetic.md). Without ``version``: the version of
    ``params`` (a ``SynthParams`` is version 1), else :data:`GENERATOR_VERSION`. ``params`` default
    to the version's own."""
    if version is None:
        version = 1 if isinstance(params, SynthParams) else GENERATOR_VERSION
    if _check_version(version) == 2:
        from snncc.data.synth_v2 import DEFAULT_PARAMS_V2, generate_v2

        return generate_v2(repetitions, seed, DEFAULT_PARAMS_V2 if params is None else params, progress)
    return generate_v1(repetitions, seed, DEFAULT_PARAMS if params is None else params, progress)


def generate_v1(
    repetitions: int = 200,
    seed: int = 0,
    params: SynthParams = DEFAULT_PARAMS,
    progress: Callable[[int], None] | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Version 1. Raw 8-bit frames ``(27 * repetitions, n_frames, 12)`` uint8 (255 at rest) and labels.

    Samples are ordered letter by letter (Space, A, ..., Z), ``repetitions`` each. ``progress`` is
    called with the number of samples finished after each letter. Seeded: the same arguments give
    the same bytes.
    """
    if repetitions < 1:
        raise SnnccError(f"repetitions must be >= 1, got {repetitions}", field="repetitions")
    p = params
    rng = np.random.default_rng(seed)
    t = np.arange(p.n_frames) / p.frame_rate_hz  # (T,)
    tx, ty, tz = TAXELS[:, 0], TAXELS[:, 1], TAXELS[:, 2]
    gain = np.exp((ty - ty.max()) / p.contact_length)  # (12,)
    two_var = 2.0 * (p.dot_sigma**2 + p.rf_sigma**2)
    frames = np.empty((N_CLASSES * repetitions, p.n_frames, 12), dtype=np.uint8)
    taxel_offset = rng.uniform(0.0, p.offset_max, size=12)
    labels = np.repeat(np.arange(N_CLASSES, dtype=np.int64), repetitions)
    for label, letter in enumerate(CLASSES):
        dots = dot_positions(letter, p)  # (D, 2)
        r = repetitions
        dx0 = rng.normal(0.0, p.start_sigma, size=r)
        onset = p.t_start + rng.normal(0.0, p.onset_sigma, size=(r, 1))
        slip = np.exp(rng.normal(0.0, p.slip_sigma, size=(r, 1)))
        s = slip * slide_offset(t[None, :], onset)  # (r, T)
        dz0 = rng.normal(0.0, p.lateral_sigma, size=r)
        force = np.exp(rng.normal(0.0, p.force_sigma, size=r))
        offset = taxel_offset + rng.normal(0.0, p.offset_jitter, size=(r, 1, 12))
        drift = rng.normal(0.0, p.drift_sigma, size=(r, 1, 12)) * t[None, :, None]
        noise = rng.normal(0.0, p.noise_sigma, size=(r, p.n_frames, 12))
        innov = rng.normal(0.0, p.wobble_sigma * np.sqrt(1.0 - p.wobble_rho**2), size=(r, p.n_frames, 12))
        wobble = np.empty_like(innov)
        wobble[:, 0] = rng.normal(0.0, p.wobble_sigma, size=(r, 12))
        for n in range(1, p.n_frames):
            wobble[:, n] = p.wobble_rho * wobble[:, n - 1] + innov[:, n]
        pressure = np.zeros((r, p.n_frames, 12))
        for xd, zd in dots:
            # dot position in the finger frame: (r, T)
            xdt = xd + dx0[:, None] - s
            zdt = zd + dz0
            d2 = (tx[None, None, :] - xdt[:, :, None]) ** 2 + (tz[None, None, :] - zdt[:, None, None]) ** 2
            pressure += np.exp(-d2 / two_var)
        pressure *= p.amplitude * gain[None, None, :] * force[:, None, None]
        load = p.saturation * (1.0 - np.exp(-pressure / p.saturation))
        signal = offset + drift + load + noise + wobble
        raw = np.clip(np.rint(255.0 - signal), 0, 255).astype(np.uint8)
        frames[label * r:(label + 1) * r] = raw
        if progress is not None:
            progress((label + 1) * r)
    return frames, labels


def params_dict(p=None, version: int = GENERATOR_VERSION) -> dict:
    """The constants as a dict (``p`` or the version's defaults)."""
    return asdict(default_params(version) if p is None else p)
