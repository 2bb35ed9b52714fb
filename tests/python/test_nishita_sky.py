"""The core's Nishita sky (cpp/firn/transport/nishita_sky.h) through the Python API: limits with exact answers,
symmetry, linearity, determinism and bad settings. Its agreement with Cycles: tests/blender/test_nishita_sky.py.

Oracles: single scattering in the optically thin limit (no attenuation), where the radiance is the scattering
column times the phase function times the sun's irradiance (Nishita et al. 1993, eq. 1 with T = 1); the
Rayleigh phase 3/(16 pi)(1 + mu^2) and Cornette & Shanks 1992's phase for g = 0.76."""

import math

import numpy as np
import pytest

import firncore

THIN = 1e-3  # density scale at which the atmosphere is optically thin (air: tau ~ 1e-4 at 380 nm)


def sky(**settings):
    return firncore.NishitaSky(**settings)


def towards(elevation, azimuth):
    """Unit direction at `elevation` above the horizon, `azimuth` (rad) from +Y turning towards +X, as the
    node's sun rotation."""
    return (math.sin(azimuth) * math.cos(elevation), math.cos(azimuth) * math.cos(elevation), math.sin(elevation))


def cornette_shanks(mu, g=0.76):
    return 3 * (1 - g * g) * (1 + mu * mu) / (8 * math.pi * (2 + g * g) * (1 + g * g - 2 * g * mu) ** 1.5)


def test_no_air_and_no_dust_leave_a_black_sky_and_an_unattenuated_sun():
    clear = dict(air_density=0.0, dust_density=0.0, ozone_density=0.0)
    for elevation in (0.05, 0.4, 1.2):
        empty = sky(sun_elevation=elevation, **clear)
        for direction in (towards(0.3, 1.0), towards(0.0, -2.0), (0, 0, 1), towards(-0.2, 0.5)):
            assert tuple(empty.radiance(direction)) == (0.0, 0.0, 0.0)
    # Nothing between the sun and the viewer: the same irradiance at any elevation and altitude.
    reference = sky(sun_elevation=0.4, **clear).sun().irradiance
    for elevation, altitude in ((0.05, 0.0), (1.2, 0.0), (0.4, 30000.0)):
        assert sky(sun_elevation=elevation, altitude=altitude, **clear).sun().irradiance == pytest.approx(
            reference, rel=1e-9)
    # The air takes light out of the beam, most in blue.
    through_air = sky(sun_elevation=0.4).sun().irradiance
    ratio = np.array(through_air) / np.array(reference)
    assert np.all(ratio < 1.0) and ratio[2] < ratio[1] < ratio[0]


def test_limb_darkening_integrated_over_the_disc():
    """E = L_centre-mean x integral of (1 - 0.6 (1 - sqrt(1 - (psi/h)^2))) cos(psi) dOmega / Omega: the ratio of
    a wide disc's irradiance to a small one's is the ratio of those integrals (numerical quadrature here)."""
    clear = dict(air_density=0.0, dust_density=0.0, ozone_density=0.0, sun_elevation=1.2)

    def mean_limb(h, n=20000):
        psi = (np.arange(n) + 0.5) / n * h
        limb = 1 - 0.6 * (1 - np.sqrt(1 - (psi / h) ** 2))
        return np.sum(limb * np.cos(psi) * np.sin(psi)) * h / n * 2 * math.pi / (2 * math.pi * (1 - math.cos(h)))

    small, wide = math.radians(0.5), math.radians(40.0)
    ratio = np.array(sky(sun_size=wide, **clear).sun().irradiance) / np.array(sky(sun_size=small, **clear).sun().irradiance)
    assert ratio == pytest.approx([mean_limb(wide / 2) / mean_limb(small / 2)] * 3, rel=1e-4)
    assert mean_limb(small / 2) == pytest.approx(0.8, rel=1e-4)  # 1 - 0.6 (1 - 2/3) for a small disc


def test_thin_air_is_rayleigh_single_scattering():
    """Sun at the zenith, thin air, no dust or ozone: L(view at zenith angle theta) = beta H m(theta) p_R E; in a
    plane-parallel atmosphere the air mass m = 1 / cos(theta), so L(60 deg) / L(0) = 2 p_R(0.5) / p_R(1) = 1.25
    (the Earth's curvature lowers the air mass at 60 deg by 0.2 %)."""
    thin = sky(sun_elevation=math.pi / 2, air_density=THIN, dust_density=0.0, ozone_density=0.0)
    zenith = np.array(thin.radiance((0.0, 0.0, 1.0)))
    slant = np.array(thin.radiance(towards(math.radians(30.0), 0.7)))
    assert slant / zenith == pytest.approx([1.25] * 3, rel=0.005)
    # Linear in the density while thin.
    thinner = sky(sun_elevation=math.pi / 2, air_density=THIN / 2, dust_density=0.0, ozone_density=0.0)
    assert np.array(thinner.radiance((0.0, 0.0, 1.0))) / zenith == pytest.approx([0.5] * 3, rel=1e-3)
    assert zenith[2] > zenith[1] > zenith[0]  # 1 / lambda^4: blue


def test_thin_dust_follows_the_cornette_shanks_phase():
    """View at the zenith, thin dust only: the sun at elevations e1, e2 changes only the scattering angle
    (mu = sin e), so the radiance ratio is the phase function's."""
    view = (0.0, 0.0, 1.0)

    def zenith(elevation):
        return np.array(sky(sun_elevation=elevation, air_density=0.0, dust_density=THIN, ozone_density=0.0)
                        .radiance(view))

    for e1, e2 in ((math.radians(80.0), math.radians(40.0)), (math.radians(60.0), math.radians(10.0))):
        expected = cornette_shanks(math.sin(e1)) / cornette_shanks(math.sin(e2))
        assert zenith(e1) / zenith(e2) == pytest.approx([expected] * 3, rel=0.01)


def test_symmetric_about_the_suns_azimuth():
    for rotation in (0.0, 1.1, -2.5):
        s = sky(sun_elevation=0.3, sun_rotation=rotation, dust_density=2.0, altitude=800.0)
        for elevation in (0.0, 0.1, 0.7, -0.2):
            for offset in (0.2, 1.0, 2.6):
                left = s.radiance(towards(elevation, rotation - offset))
                right = s.radiance(towards(elevation, rotation + offset))
                assert left == pytest.approx(right, rel=1e-9, abs=1e-12)
    # The sky is brightest towards the sun (forward scattering) and the disc lies where the sun is.
    s = sky(sun_elevation=0.3, sun_rotation=1.1)
    assert sum(s.radiance(towards(0.3, 1.1 + 0.05))) > sum(s.radiance(towards(0.3, 1.1 + math.pi)))
    assert s.sun_direction == pytest.approx(towards(0.3, 1.1))
    assert sum(s.sun_disc_radiance(s.sun_direction)) > 1e4 * sum(s.radiance(towards(0.3, 1.2)))
    assert tuple(s.sun_disc_radiance(towards(0.3, 1.2))) == (0.0, 0.0, 0.0)


def test_below_the_horizon_the_horizon_fades_out():
    """Blender's ground: the horizon's colour times (1 + 2.5 z)^3 down to z = -0.4, black below."""
    s = sky(sun_elevation=0.2)
    horizon = np.array(s.radiance(towards(0.0, 2.0)))
    z = -0.2
    assert np.array(s.radiance(towards(math.asin(z), 2.0))) == pytest.approx(horizon * (1 + 2.5 * z) ** 3, rel=1e-9)
    assert tuple(s.radiance(towards(math.asin(-0.45), 2.0))) == (0.0, 0.0, 0.0)


def test_strength_and_intensity_scale_linearly():
    base = sky(sun_elevation=0.5)
    strong = sky(sun_elevation=0.5, strength=3.0, sun_intensity=0.5)
    d = towards(0.4, 2.0)
    assert np.array(strong.radiance(d)) == pytest.approx(3.0 * np.array(base.radiance(d)), rel=1e-12)
    assert np.array(strong.sun().irradiance) == pytest.approx(1.5 * np.array(base.sun().irradiance), rel=1e-12)


def test_no_sun_when_off_dark_or_set():
    assert sky(sun_disc=False).sun() is None
    assert sky(sun_intensity=0.0).sun() is None
    assert sky(sun_elevation=-0.05).sun() is None  # the whole disc below the horizon
    half_set = sky(sun_elevation=0.0).sun()  # half the disc above the horizon
    assert half_set is not None and half_set.angular_diameter == pytest.approx(math.radians(0.545))


def test_map_is_the_radiance_per_pixel_in_the_sky_convention_and_deterministic():
    s = sky(sun_elevation=0.35, sun_rotation=0.8, dust_density=1.5)
    width, height = 32, 16
    first = s.map(None, width, height, samples=1)
    assert first.shape == (height, width, 3) and first.dtype == np.float32
    assert np.array_equal(first, s.map(None, width, height, samples=1))
    # Pixel (i, j), row 0 at the bottom, centred at u = (i + 1/2) / W, v = (j + 1/2) / H (lights.h).
    for i, j in ((3, 12), (20, 9), (31, 0)):
        u, v = (i + 0.5) / width, (j + 0.5) / height
        phi, elevation = 2 * math.pi * (0.5 - u), math.pi * (v - 0.5)
        d = (math.cos(elevation) * math.cos(phi), math.cos(elevation) * math.sin(phi), math.sin(elevation))
        assert first[j, i] == pytest.approx(s.radiance(d), rel=1e-6)
    # A frame turned a quarter about +Z: its +X is the world's +Y.
    turn = np.array([[0.0, -1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]])
    turned = s.map(turn, width, height, samples=1)
    row = 10
    assert turned[row, width // 2 - 1] == pytest.approx(first[row, width // 4 - 1], rel=1e-5)


@pytest.mark.parametrize("bad", [dict(altitude=-1.0), dict(altitude=70000.0), dict(air_density=11.0),
                                 dict(dust_density=-0.1), dict(ozone_density=float("nan")),
                                 dict(sun_elevation=2.0), dict(sun_size=-0.1), dict(strength=-1.0)])
def test_bad_settings_are_refused(bad):
    with pytest.raises(ValueError):
        sky(**bad).map(None, 8, 4)
    with pytest.raises(ValueError):
        sky(**bad).sun()


def test_bad_map_sizes_and_directions_are_refused():
    with pytest.raises(ValueError):
        sky().map(None, 0, 4)
    with pytest.raises(ValueError):
        sky().map(None, 8, 4, samples=0)
    with pytest.raises(ValueError):
        sky().map(np.eye(2), 8, 4)
    with pytest.raises(TypeError):
        firncore.NishitaSky(sun_height=1.0)
    with pytest.raises(ValueError):
        sky().radiance((0.0, 0.0, 0.0))
    with pytest.raises(ValueError):
        sky().sun_disc_radiance((float("nan"), 0.0, 1.0))
