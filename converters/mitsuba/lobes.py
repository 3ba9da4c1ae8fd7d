"""The Phong lobe of the path tracer's materials (tracer/cpp/20_path.h), in a BSDF's local frame
(the shading normal is +z), shared by the ``rtlab_phong`` and ``rtlab_mixed_lobes`` plugins."""

from __future__ import annotations

from typing import Any

import drjit as dr
import mitsuba as mi


def mirror_direction(wi: Any) -> Any:
    """wi reflected about the local normal +z: the centre of the Phong lobe."""
    return mi.Vector3f(-wi.x, -wi.y, wi.z)


def phong_lobe(mirror: Any, wo: Any, shininess: float) -> Any:
    """max(cos a, 0)^n, a the angle between wo and the mirror direction."""
    return dr.power(dr.maximum(dr.dot(mirror, wo), 0.0), shininess)


def phong_f(specular: float, shininess: float, lobe: Any) -> Any:
    """The normalised Phong lobe's value: specular (n + 2) / (2 pi) cos^n a."""
    return specular * (shininess + 2) / (2 * dr.pi) * lobe


def phong_pdf(shininess: float, lobe: Any, probability: float = 1.0) -> Any:
    """The density of sampling cos^n a about the mirror direction, (n + 1) / (2 pi) cos^n a,
    times the probability of choosing the lobe at all."""
    return probability * (shininess + 1) / (2 * dr.pi) * lobe


def sample_phong_lobe(mirror: Any, sample2: Any, shininess: float) -> Any:
    """A direction drawn with density phong_pdf about the mirror direction: cos a = u^(1/(n+1)),
    the azimuth uniform."""
    c = dr.power(sample2.x, 1 / (shininess + 1))
    s = dr.safe_sqrt(1 - c * c)
    phi = 2 * dr.pi * sample2.y
    return mi.Frame3f(mirror).to_world(mi.Vector3f(s * dr.cos(phi), s * dr.sin(phi), c))
