"""A snow object's optics as the core computes them: the one place that turns obj.firn into firncore calls.

No physics here: unit conversion (ng/g, µg/g to mass fractions) and the choice between PHYSICAL and CUSTOM.
"""

from dataclasses import dataclass

from ..common.core import firncore

KG_PER_KG_PER_NG_PER_G = 1e-9
KG_PER_KG_PER_UG_PER_G = 1e-6


def volume_optics(settings):
    """firncore.VolumeOptics of a snow object's settings (obj.firn); ValueError when they are not snow."""
    if settings.optics_mode == "CUSTOM":
        return firncore.VolumeOptics(settings.extinction_per_density, tuple(settings.albedo), settings.anisotropy)
    return firncore.optics(
        grain_radius=settings.grain_radius,
        density=settings.mean_density,
        black_carbon=settings.impurity_black_carbon * KG_PER_KG_PER_NG_PER_G,
        dust=settings.impurity_dust * KG_PER_KG_PER_UG_PER_G,
        liquid_water=settings.liquid_water,
        B=settings.absorption_enhancement,
        g=settings.anisotropy,
    )


def physical_default(grain_radius, density, g):
    """Optics of clean, dry snow: what the CUSTOM fields start from."""
    return firncore.optics(grain_radius=grain_radius, density=density, g=g)


@dataclass
class Derived:
    """What the panel shows about a snow object's optics, at its mean density; `error` says why there is none."""

    error: str = None
    sigma_t: float = 0.0  # 1/m
    albedo: tuple = (0.0, 0.0, 0.0)  # single-scattering omega per channel
    co_albedo: tuple = (0.0, 0.0, 0.0)  # 1 - omega
    white_sky_albedo: tuple = (0.0, 0.0, 0.0)
    diffusion_length: tuple = (0.0, 0.0, 0.0)  # m
    transport_mean_free_path: float = 0.0  # m (the channels agree to 1e-4)


def derived(settings):
    try:
        volume = volume_optics(settings)
    except ValueError as error:
        return Derived(error=str(error))
    density = settings.mean_density
    return Derived(
        sigma_t=volume.sigma_t(density),
        albedo=volume.albedo,
        co_albedo=volume.co_albedo,
        white_sky_albedo=volume.white_sky_albedo,
        diffusion_length=volume.diffusion_length(density),
        transport_mean_free_path=volume.transport_mean_free_path(density)[1],
    )
