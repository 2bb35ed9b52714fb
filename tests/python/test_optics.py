"""Snow optics through firncore under plain /usr/bin/python3: the issue's checks, the API, bad input."""

import math

import pytest

import firncore

RHO_ICE = 917.0  # kg/m^3


def test_snowoptics_regression():
    # snowoptics (Picard) regression: KZ04, Warren & Brandt 2008 ice, 800 nm, solar zenith 45 deg,
    # SSA 20 m^2/kg, 10 % diffuse light -> 0.8905460508683.
    albedo = firncore.kz04_albedo(800e-9, math.cos(math.radians(45)), 0.1, ssa=20.0)
    assert albedo == pytest.approx(0.8905460508683, abs=1e-5)


def test_mixed_albedo_is_the_mix_of_plane_and_spherical():
    mu0 = math.cos(math.radians(60))
    plane = firncore.kz04_plane_albedo(600e-9, mu0, grain_radius=200e-6)
    spherical = firncore.kz04_spherical_albedo(600e-9, grain_radius=200e-6)
    assert firncore.kz04_albedo(600e-9, mu0, 0.3, grain_radius=200e-6) == pytest.approx(0.7 * plane + 0.3 * spherical)
    # KZ04: r_p(mu0) = r_s^(3/7 (1 + 2 mu0)); at mu0 = 0.5 the exponent is 6/7 (brighter than white-sky).
    assert plane == pytest.approx(spherical ** (6 / 7))


def test_extinction_is_geometric_optics():
    # sigma_t = 3 rho / (2 rho_ice r) exactly, r = 100 um, rho = 300 kg/m^3.
    optics = firncore.optics(grain_radius=100e-6, density=300.0)
    assert optics.sigma_t(300.0) == 3 * 300.0 / (2 * RHO_ICE * 100e-6)
    assert optics.extinction_per_density * 300.0 == pytest.approx(4907.3064, rel=1e-7)


def test_fresh_clean_snow_is_white_and_slightly_blue():
    for radius in (50e-6, 100e-6):
        red, green, blue = firncore.optics(grain_radius=radius, density=100.0).white_sky_albedo
        assert min(red, green, blue) > 0.95
        assert blue >= green >= red


def test_black_carbon_lowers_albedo_monotonically():
    previous = (1.0, 1.0, 1.0)
    for ng_per_g in (0, 2, 20, 200, 2000):
        albedo = firncore.optics(grain_radius=100e-6, density=300.0, black_carbon=ng_per_g * 1e-9).white_sky_albedo
        assert all(a < p for a, p in zip(albedo, previous)), (ng_per_g, albedo, previous)
        previous = albedo


def test_larger_grains_lower_albedo():
    previous = (1.0, 1.0, 1.0)
    for radius in (40e-6, 100e-6, 250e-6, 600e-6, 1500e-6):
        albedo = firncore.optics(grain_radius=radius, density=300.0).white_sky_albedo
        assert all(a < p for a, p in zip(albedo, previous)), (radius, albedo, previous)
        previous = albedo


def test_spectral_albedo_falls_towards_the_red():
    # Ice absorbs ~3000 times more at 800 nm than at 400 nm (Warren & Brandt 2008).
    albedos = [firncore.kz04_spherical_albedo(nm * 1e-9, grain_radius=300e-6) for nm in range(400, 801, 50)]
    assert albedos == sorted(albedos, reverse=True)
    assert firncore.ice_absorption(800e-9) / firncore.ice_absorption(400e-9) > 2000


def test_ssa_and_radius_are_the_same_snow():
    radius = firncore.grain_radius_from_ssa(25.0)
    assert radius == pytest.approx(3 / (RHO_ICE * 25.0))
    a = firncore.kz04_spherical_albedo(550e-9, ssa=25.0)
    b = firncore.kz04_spherical_albedo(550e-9, grain_radius=radius)
    assert a == pytest.approx(b, rel=1e-12)


def test_liquid_water_darkens_and_needs_density():
    dry = firncore.optics(grain_radius=500e-6, density=400.0)
    wet = firncore.optics(grain_radius=500e-6, density=400.0, liquid_water=0.06)
    assert all(w < d for w, d in zip(wet.white_sky_albedo, dry.white_sky_albedo))
    # The water adds mass without surface: extinction per kilogram drops with the ice's share of the mass.
    assert wet.extinction_per_density == pytest.approx(dry.extinction_per_density * (400.0 - 60.0) / 400.0)
    with pytest.raises(ValueError, match="density"):
        firncore.kz04_spherical_albedo(550e-9, grain_radius=500e-6, liquid_water=0.06)
    # Dry snow's albedo does not depend on density, so it may be left out.
    assert firncore.kz04_spherical_albedo(550e-9, grain_radius=500e-6) == pytest.approx(
        firncore.kz04_spherical_albedo(550e-9, grain_radius=500e-6, density=150.0))


def test_volume_optics_made_directly():
    optics = firncore.VolumeOptics(10.0, (0.9, 0.95, 0.99), 0.5)
    assert optics.albedo == (0.9, 0.95, 0.99)
    assert optics.co_albedo == pytest.approx((0.1, 0.05, 0.01))
    assert optics.sigma_t(200.0) == 2000.0
    mfp = optics.transport_mean_free_path(200.0)
    assert mfp[0] == pytest.approx(1 / (2000.0 * (1 - 0.9 * 0.5)))
    length = optics.diffusion_length(200.0)
    assert length[2] == pytest.approx(1 / math.sqrt(3 * 2000.0 * 0.01 * 2000.0 * (1 - 0.99 * 0.5)))
    assert "VolumeOptics(" in repr(optics)
    with pytest.raises(AttributeError):
        optics.g = 0.3  # immutable: validated once


def test_real_snow_scales():
    # Fresh snow at 250 kg/m^3: sigma_t in the thousands per metre, transport mean free path ~1.6 mm,
    # diffusion length of centimetres to decimetres (red shortest).
    optics = firncore.optics(grain_radius=100e-6, density=250.0)
    assert 500 < optics.sigma_t(250.0) < 5000
    assert optics.transport_mean_free_path(250.0)[1] == pytest.approx(1.58e-3, rel=0.01)
    red, green, blue = optics.diffusion_length(250.0)
    assert 0.02 < red < green < blue


def test_colour_matching_maps_flat_to_grey():
    grid = firncore.spectral_grid()
    assert grid[0] == pytest.approx(390e-9) and grid[-1] == pytest.approx(800e-9) and len(grid) == 42
    assert firncore.reflectance_to_rgb([0.42] * len(grid)) == pytest.approx((0.42, 0.42, 0.42), abs=1e-14)
    with pytest.raises(ValueError, match="spectral_grid"):
        firncore.reflectance_to_rgb([0.5] * 10)


def test_tables():
    n, kappa = firncore.ice_refractive_index(550e-9)
    assert (n, kappa) == (pytest.approx(1.311), pytest.approx(2.289e-9))
    assert firncore.ice_absorption(550e-9) == pytest.approx(4 * math.pi * 2.289e-9 / 550e-9)
    assert firncore.water_absorption(550e-9) == pytest.approx(0.0565)  # Pope & Fry 1997


@pytest.mark.parametrize(
    "kwargs, words",
    [
        (dict(grain_radius=-1e-4, density=300.0), "grain radius"),
        (dict(grain_radius=0.0, density=300.0), "grain radius"),
        (dict(grain_radius=float("nan"), density=300.0), "grain radius"),
        (dict(grain_radius=1e-4, density=0.0), "density"),
        (dict(grain_radius=1e-4, density=1200.0), "density"),
        (dict(grain_radius=1e-4), "density"),
        (dict(density=300.0), "exactly one"),
        (dict(grain_radius=1e-4, ssa=30.0, density=300.0), "exactly one"),
        (dict(ssa=-30.0, density=300.0), "specific surface area"),
        (dict(grain_radius=1e-4, density=300.0, black_carbon=-1e-9), "black carbon"),
        (dict(grain_radius=1e-4, density=300.0, dust=-1e-6), "dust"),
        (dict(grain_radius=1e-4, density=300.0, liquid_water=-0.1), "liquid water"),
        (dict(grain_radius=1e-4, density=200.0, liquid_water=0.25), "leaving no ice"),
        (dict(grain_radius=1e-3, density=300.0, black_carbon=0.05), "impurities absorb more"),
        (dict(grain_radius=1e-4, density=300.0, g=1.0), "asymmetry"),
        (dict(grain_radius=1e-4, density=300.0, B=-1.0), "absorption enhancement"),
    ],
)
def test_bad_input_is_a_value_error(kwargs, words):
    with pytest.raises(ValueError, match=words):
        firncore.optics(**kwargs)


def test_bad_wavelength_and_geometry():
    with pytest.raises(ValueError, match="wavelength"):
        firncore.kz04_spherical_albedo(1000e-9, grain_radius=1e-4)
    with pytest.raises(ValueError, match="wavelength"):
        firncore.ice_absorption(550.0)  # nanometres by mistake: the API is in metres
    with pytest.raises(ValueError, match="zenith"):
        firncore.kz04_plane_albedo(550e-9, -0.2, grain_radius=1e-4)
    with pytest.raises(ValueError, match="diffuse fraction"):
        firncore.kz04_albedo(550e-9, 0.5, 1.2, grain_radius=1e-4)
    with pytest.raises(ValueError, match="albedo"):
        firncore.VolumeOptics(10.0, (1.2, 0.5, 0.5), 0.8)
    with pytest.raises(ValueError, match="anisotropy"):
        firncore.VolumeOptics(10.0, (0.5, 0.5, 0.5), 1.0)
    with pytest.raises(ValueError, match="extinction"):
        firncore.VolumeOptics(-1.0, (0.5, 0.5, 0.5), 0.0)


def test_docs_preset_tables_match_the_core():
    """docs/optics.md lists each preset's parameters and what they give: the numbers must be the core's."""
    import pathlib
    import re

    text = (pathlib.Path(__file__).resolve().parents[2] / "docs" / "optics.md").read_text(encoding="utf-8")

    def table(header):
        rows = text[text.index(header):].split("\n\n")[0].splitlines()[2:]
        return [[cell.strip() for cell in row.strip("|").split("|")] for row in rows]

    parameters = {row[0]: [float(cell) for cell in row[1:5]] for row in table("| Preset | Grain radius")}
    results = table("| Preset | σt (1/m)")
    assert len(results) == len(parameters) >= 6
    for name_and_density, sigma_t, white_sky, diffusion, mfp in results:
        name, density = re.fullmatch(r"(.+) \((\d+)(?: kg/m³)?\)", name_and_density).groups()
        radius_um, black_carbon, dust, water = parameters[name]
        density = float(density)
        optics = firncore.optics(grain_radius=radius_um * 1e-6, density=density, black_carbon=black_carbon * 1e-9,
                                 dust=dust * 1e-6, liquid_water=water)
        assert float(sigma_t) == pytest.approx(optics.sigma_t(density), abs=0.5), name
        assert [float(v) for v in white_sky.split(",")] == pytest.approx(optics.white_sky_albedo, abs=5e-4), name
        assert [float(v) for v in diffusion.split(",")] == pytest.approx(
            [100 * d for d in optics.diffusion_length(density)], abs=0.05), name
        assert float(mfp) == pytest.approx(1000 * optics.transport_mean_free_path(density)[1], abs=0.005), name


@pytest.mark.parametrize("grain_radius, black_carbon", [(100e-6, 0.0), (500e-6, 0.0), (200e-6, 500e-9)])
def test_far_surface_albedo_is_the_volumes_plane_albedo_under_a_uniform_sky(grain_radius, black_carbon):
    """Far snow renders as a diffuse surface of the white-sky albedo (snow_layer/operators.py write_bands, render
    mode Opaque). The volume it replaces, a deep layer of the same optics, reflects of a uniform sky the photon
    Monte Carlo's reflectance (the core's independent oracle): equal within 2 % in every channel. 50 cm of snow at
    200 kg/m³ over black ground reflects less (light leaves through the bottom: +2.0 % in blue at 0.5 mm grains,
    measured), within 3 % and never more than the surface beyond the oracle's noise."""
    optics = firncore.optics(grain_radius=grain_radius, density=200.0, black_carbon=black_carbon)
    for depth, below, above in ((float("inf"), -0.02, 0.02), (0.5, 0.0, 0.03)):  # m; surface / volume - 1
        tau = optics.sigma_t(200.0) * depth
        for channel in range(3):
            slab = firncore.slab_monte_carlo(omega=optics.albedo[channel], g=optics.g, tau=tau, mu0=-1.0,
                                             photons=16000, seed=channel)
            noise = 3 * slab["reflectance_error"]
            assert noise < 0.01  # the oracle's own noise is well inside the tolerances
            excess = optics.white_sky_albedo[channel] / slab["reflectance"] - 1.0
            assert below - noise <= excess <= above, (depth, channel)
