"""The liquid-bridge law of a run as the granule analysis applies it.

:class:`Liquid` is the law the engine applied in one case (the model of
:mod:`ligwf.liquids`, the CG-scaled surface tension, the contact angle the engine actually
used, see :mod:`ligwf.liquids.contact_angle`); the functions evaluate it on the pairs of a dumped
frame with the model's numpy law (the reference the compiled kernels are tested against).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ligwf import liquids
from ligwf.analysis.frames.dumps import ParticleFrame
from ligwf.liquids.contact_angle import applied_contact_angle_rad
from ligwf.liquids.base import LiquidModel, LiquidSettings
from ligwf.scene.scaled import ScaledScene


@dataclass(frozen=True)
class Liquid:
    """The liquid-bridge law the engine applied in a run (from the case's scaled scene)."""

    model: str                  # a name of ligwf.liquids' registry
    surface_tension: float      # N/m, already CG-scaled
    contact_angle_rad: float    # the angle the engine APPLIED (see ligwf.liquids.contact_angle)
    liquid_content: float       # fraction of particle volume, used if a dump lacks it
    #: the model's own settings in the run (its settings_type; None: the model's defaults)
    settings: LiquidSettings | None = None

    @property
    def law(self) -> LiquidModel:
        """The liquid model (its force law, bridge volume and rupture distance) at the run's
        settings."""
        return liquids.get(self.model).configured(self.settings)

    @classmethod
    def from_scaled(cls, scaled: ScaledScene, engine_product_bug: bool = True) -> "Liquid":
        """The law of a scaled case. ligwf writes a compensated input angle so the 3.8.0
        engine applies the scene angle; without compensation it applied 0.5 a^2."""
        liq = scaled.liquid_values
        liquids.get(liq.model)          # an unknown model is an error here
        theta = applied_contact_angle_rad(liq.contact_angle_deg, liq.contact_angle_compensation,
                                          engine_product_bug)
        return cls(liq.model, float(liq.surface_tension), theta, float(liq.liquid_content),
                   liq.settings)


def content_of(particles: ParticleFrame, liquid: Liquid) -> np.ndarray:
    """Liquid content per particle: the dump's, or the scene's when the dump lacks it; as
    the engine uses it in a pair (the law's ``clip_content``: washino's liquid cap)."""
    content = particles.liquid_content
    if content is None:
        content = np.full(len(particles), liquid.liquid_content)
    return liquid.law.clip_content(np.asarray(content, dtype=np.float64))


def pair_forces(particles: ParticleFrame, i: np.ndarray, j: np.ndarray, gap: np.ndarray,
               liquid: Liquid) -> np.ndarray:
    law = liquid.law
    if not law.wet or len(i) == 0:
        return np.zeros(len(i))
    content = content_of(particles, liquid)
    with np.errstate(divide="ignore", invalid="ignore"):
        force = np.asarray(law.capillary_force(
            particles.radii[i], particles.radii[j], gap,
            liquid.surface_tension, liquid.contact_angle_rad, content[i], content[j]), dtype=float)
    # two dry particles (placed liquid: a dry bed around wet granules) hold no bridge
    return np.where((content[i] > 0) | (content[j] > 0), force, 0.0)


def force_law_positive(particles: ParticleFrame, liquid: Liquid, content: np.ndarray) -> bool:
    """True when the capillary law is > 0 N for EVERY pair of this frame within rupture
    distance, so that with ``min_bridge_force`` = 0 the bond test need not evaluate it
    (the model's proof, ``force_positive``, over the frame's radii and contents)."""
    if len(particles) == 0:
        return False
    return liquid.law.force_positive(
        liquid.surface_tension, liquid.contact_angle_rad, float(particles.radii.min()),
        float(particles.radii.max()), float(content.min()), float(content.max()))


#: Gauss-Legendre nodes of the rupture-work quadrature: the laws are smooth between contact
#: and rupture (16 nodes reproduce the exact integral of a polynomial of degree 31)
WORK_NODES = 16


def work_limits(particles: ParticleFrame, i: np.ndarray, j: np.ndarray, gap: np.ndarray,
                liquid: Liquid) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(lower gap max(gap, 0), rupture gap, bridge volume) of pairs i, j (m, m, m^3): the
    interval over which :func:`relative_energy` integrates the force."""
    law = liquid.law
    content = content_of(particles, liquid)
    vol = np.asarray(law.bridge_volume(particles.radii[i], particles.radii[j], content[i],
                                       content[j]), dtype=float)
    hi = np.asarray(law.rupture_distance(vol, liquid.contact_angle_rad), dtype=float)
    return np.minimum(np.maximum(gap, 0.0), hi), hi, vol


def relative_energy(particles: ParticleFrame, i: np.ndarray, j: np.ndarray, gap: np.ndarray,
                    liquid: Liquid, implementation: str = "fast") -> np.ndarray:
    """e_rel = W / (F_0 R*): the work the bridge of each pair (rows i, j, gap m) still does
    before it ruptures, W = integral of F from max(gap, 0) to the rupture gap (the law's,
    which the engine applies), over that of a unit force scale F_0 = 2 pi R* gamma cos theta
    times R*. Dimensionless and unchanged by CG scaling under both rules (W ~ F x gap
    scales like F_0 R*), and unlike the touching force it grows with the bridge volume
    (the rupture gap goes like V^(1/3)): the energy needed to pull the pair apart, the
    quantity that decides whether a bridge survives a collision. A touching pair counts
    from gap 0 (the overlap part is the Hertz contact's business). ``fast``: compiled
    quadrature with the model's numba law; ``reference``: the model's numpy law at the
    same nodes."""
    law = liquid.law
    if not law.wet or len(i) == 0:
        return np.zeros(len(i))
    lo, hi, vol = work_limits(particles, i, j, gap, liquid)
    nodes, weights = np.polynomial.legendre.leggauss(WORK_NODES)
    r_i, r_j = particles.radii[i], particles.radii[j]
    if implementation == "fast":
        from ligwf.analysis.granules_numba import rupture_work

        work = rupture_work(r_i, r_j, lo, hi, vol, law.kernels.force,
                            float(liquid.surface_tension), float(liquid.contact_angle_rad),
                            nodes, weights)
    elif implementation == "reference":
        content = content_of(particles, liquid)
        half, mid = 0.5 * (hi - lo), 0.5 * (hi + lo)
        work = np.zeros(len(i))
        for x, w in zip(nodes, weights):
            work += w * np.asarray(law.capillary_force(
                r_i, r_j, mid + half * x, liquid.surface_tension, liquid.contact_angle_rad,
                content[i], content[j]), dtype=float)
        work *= half
    else:
        raise ValueError(f"implementation {implementation!r}: use fast or reference")
    r_eff = r_i * r_j / (r_i + r_j)
    return work / (2.0 * np.pi * r_eff * r_eff * liquid.surface_tension
                   * np.cos(liquid.contact_angle_rad))


def relative_force(force: np.ndarray, r_i: np.ndarray, r_j: np.ndarray, liquid: Liquid) -> np.ndarray:
    """f_rel = F / (2 pi R* gamma cos theta): a bridge force (N) over the force of a
    touching bridge of the same pair (R* = r_i r_j / (r_i + r_j), m; gamma the case's
    scaled surface tension, theta the applied contact angle). Dimensionless, so one
    threshold or weight means the same at every CG level and under every rule."""
    r_eff = r_i * r_j / (r_i + r_j)
    return force / (2.0 * np.pi * r_eff * liquid.surface_tension
                    * np.cos(liquid.contact_angle_rad))
