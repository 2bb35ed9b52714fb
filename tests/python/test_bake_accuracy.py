"""The bake on small and thin snow shapes against the core's brute-force Monte Carlo: a reduced set of
bench/bake_suite.py (docs/bake.md, Accuracy on small and thin shapes).

Oracles: `firncore.monte_carlo_radiance` (all orders, exact Henyey-Greenstein phase function, none of the bake's
approximations; seeded, so its noise is fixed), and for a non-absorbing medium under a uniform sky the exact
isotropic field (every point sees the sky's radiance L from every direction, so the source function is L), and
energy conservation (where the snow absorbs nothing, every watt of sun entering a ball leaves it)."""

import dataclasses
import functools
import itertools
import math
import os
import shutil
import sys
import tempfile

import numpy as np
import pytest

import firncore

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "bench"))
import bake_flat_slab  # noqa: E402
import bake_suite  # noqa: E402
import bake_terminator  # noqa: E402
import ball_energy_balance  # noqa: E402
import lamp_slab_pieces  # noqa: E402
import lamp_terminator  # noqa: E402
import plateau_sun_profile  # noqa: E402


def case(name):
    return next(c for c in bake_suite.cases() if c.name == name)


@functools.cache
def suite_run(folder, name, samples, views=None, seed=0):
    """bake_suite.run_case of the suite's case `name` at bake `seed` against a reference of `samples` paths per block
    (the suite's cached ones take up to 16384: less noise; these suffice here), seen from `views` (a tuple) or the
    case's own. Computed once for the module: the bake and the Monte Carlo are seeded, so the tests that read the same
    run share it; its reference is kept in `folder` for the case's other seeds."""
    c = case(name)
    c.samples = samples
    if views is not None:
        c.views = list(views)
    return bake_suite.run_case(c, folder, os.path.join(folder, "references"), seed=seed)


def baked_against_reference(folder, name, samples, views=None):
    """The suite's case `name` baked (seed 0) and rendered against a fresh reference of `samples` paths per block,
    seen from `views` or the case's own."""
    return suite_run(folder, name, samples, None if views is None else tuple(views))


def over_seeds_against_reference(folder, name, samples, seeds):
    """The suite's case `name` baked with seeds 0..seeds-1 against one fresh reference of `samples` paths per block,
    as bake_suite.over_seeds sums them."""
    return bake_suite.over_seeds([suite_run(folder, name, samples, seed=seed) for seed in range(seeds)])


@functools.cache
def sun_alone_baked(folder, name):
    """The suite's case `name` baked (FINAL, seed 0) under its sun alone, once for the module: the file's path."""
    c = case(name)
    path = os.path.join(folder, f"{name}_sun_alone.vdb")
    bake_suite.write_density(path, c.density, c.voxel)
    firncore.bake(path, c.optics, suns=c.suns(), quality="FINAL", seed=0)
    return path


def sun_alone_against_monte_carlo(folder, name, blocks, samples=4096):
    """The suite's case `name` under its sun alone, seen against the sun (view (180, 0)): the baked render's sum
    over `blocks` against the core's Monte Carlo's (`samples` paths per block, seed 31), relative (green)."""
    c = case(name)
    origins, directions, _ = bake_suite.views(c)
    pick = [c.views.index((180, 0)) * c.pixels ** 2 + b for b in blocks]
    path = sun_alone_baked(folder, name)
    baked = firncore.render_baked(path, c.optics, origins[pick], directions[pick])[:, 1].sum()
    truth, _ = firncore.monte_carlo_radiance(path, c.optics, origins[pick], directions[pick], suns=c.suns(),
                                             samples=samples, seed=31)
    return baked / truth[:, 1].sum() - 1


@functools.cache
def lamp_row(folder, kind):
    """bench/lamp_terminator.py's row of ball_grey under lamp `kind` against 1024 Monte Carlo paths per block, once for
    the module."""
    return lamp_terminator.measure(case("ball_grey"), kind, folder, cache=None, samples=1024)


@pytest.fixture(scope="module")
def folder():
    with tempfile.TemporaryDirectory() as path:
        yield path


def test_conservative_thin_ball_under_uniform_sky_glows_with_the_sky(tmp_vdb):
    # omega = 1, g = 0, uniform sky L: the radiance is L everywhere in every direction (the isotropic field
    # solves the transport equation with this boundary), so a camera ray shows L (1 - exp(-tau)) exactly.
    # Voxels of optical depth 1: all of them take the Monte Carlo source, which here has no variance.
    density = bake_suite.ball(0.04, 0.01) * 100.0
    bake_suite.write_density(tmp_vdb, density, 0.01)
    optics = firncore.VolumeOptics(1.0, (1.0, 1.0, 1.0), 0.0)  # sigma_t 100 /m
    stats = firncore.bake(tmp_vdb, optics, sky=firncore.Sky((0.5, 0.5, 0.5)), seed=3)
    assert stats["traced_voxels"] == int((density > 0).sum())
    centre = (np.array(density.shape) - 1) / 2 * 0.01
    origins = np.array([centre + [0.5, 0.0, dz] for dz in (0.0, 0.015, 0.03)])
    directions = np.tile([-1.0, 0.0, 0.0], (3, 1))
    radiance = firncore.render_baked(tmp_vdb, optics, origins, directions)[:, 1]
    steps = np.linspace(0.0, 1.0, 4001)
    tau = [bake_suite.trilinear(density, (o + steps[:, None] * d) / 0.01).sum() * (steps[1] - steps[0])
           for o, d in zip(origins, directions)]
    assert radiance == pytest.approx([0.5 * (1.0 - math.exp(-t)) for t in tau], rel=0.01)


@pytest.mark.parametrize("name, mean, bias", [
    ("ball_sky", 0.05, 0.05),       # the goal; measured 2.8 %, -2.1 % (reference noise 0.9 %)
    ("ball_half_tau", 0.05, 0.05),  # the goal; measured 4.0 %, -2.4 % (noise 2.6 %; 4.9 % with the linear form)
    # Thin balls, every voxel traced. Read as one lobe, the traced source took them from 14.0 % (g 0.5) and 43.8 %
    # (g 0.85, under one transport mean free path) with the linear form to 8.8 % and 16.3 %; with the beams'
    # single scattering in the second, peaked lobe to 4.8 % (the goal) and 15.4 %, bias -2.1 % and -7.1 %
    # against the suite's 16384-path references. ball_thin_forward stays short of the goal, guarded: 15.4 %, bias
    # -7.1 % with the peaked lobe holding the beams' single scattering only, 9.1 %, +0.2 % with the two lobes
    # fitted to the source's first four Legendre moments (traced_source.h, tracedSourceByMoments); 7.0 %, +0.5 %
    # (ball_thin 4.0 %) over 4 seeds with 1024 paths per voxel where that is cheap (bake_traced_voxels.cpp,
    # planGathering).
    ("ball_thin", 0.06, 0.05),
    ("ball_thin_forward", 0.12, 0.05),
])
def test_small_balls_match_monte_carlo(folder, name, mean, bias):
    result = baked_against_reference(folder, name, min(case(name).samples, 2048))
    assert result["mean"] < mean
    assert abs(result["bias"]) < bias


@pytest.mark.parametrize("g, sigma_t", [(0.0, 600.0), (0.85, 2000.0), (0.85, 6000.0)])
def test_small_ball_that_absorbs_nothing_lets_out_the_sun_that_enters_it(g, sigma_t):
    # Energy conservation: at omega 1 - 1e-7 every watt of sun entering the ball leaves it (E times its
    # cross-section sum (1 - T) dA; the leaving power over 100 views spread evenly over the sphere). The 5 cm ball on
    # 1 cm voxels is a small ball (kSkyRampRadius), here at 6, 20 and 60 optical depths per voxel. With its carried sun
    # undivided it let out 1.057, 1.094 and 1.068 W per W entering; divided as carriedSunSpread gives, 1.013, 1.034
    # and 0.999 (docs/benchmarks.md, lead-91); since the ramp's grazing sun is delta-scaled and the exponent 3/4,
    # 0.992, 1.023, 0.977 (with the exponent 1/2 left: 1.013, 1.051, 1.008; lead-92).
    c = dataclasses.replace(case("ball_iso"), omega=(0.9999999,) * 3, g=g, sigma_t=sigma_t)
    assert ball_energy_balance.sun_balance(c) == pytest.approx(1.0, abs=0.05)


def test_absorbing_ball_lets_out_its_limbs_forward_light(folder):
    # The 5 cm ball at omega 0.9, g 0.85, 20 optical depths per voxel, under the sun: of the 100 views spread evenly
    # over the sphere, the 6 within 30 degrees of the sun's travel (150-180 degrees from the sun, 22 % of the power
    # leaving) see its limb's forward light. The power towards them, baked over the core's Monte Carlo on the same
    # rays (64 paths per ray, seed 11; bench/ball_energy_balance.py --mc-views): with the ramp's single scattering of
    # the grazing sun uncollided (rampBeamCrossing returning Crossing::Uncollided, temporarily) 0.712, delta-scaled
    # (beamsInRamp, rampBeamCrossing) 0.837 (docs/benchmarks.md, lead-92).
    c = dataclasses.replace(case("ball_issue"), omega=(0.9,) * 3, sigma_t=2000.0)
    path = os.path.join(folder, "absorbing.vdb")
    bake_suite.write_density(path, c.density, c.voxel)
    firncore.bake(path, c.optics, quality="FINAL", seed=0, suns=c.suns())
    backs = ball_energy_balance.fibonacci(100)
    backs = backs[backs @ np.asarray(ball_energy_balance.sun_towards()) < -math.sqrt(3.0) / 2.0]
    baked = ball_energy_balance.baked_power(c, path, backs, 16)
    traced = ball_energy_balance.traced_power(c, path, {"suns": c.suns()}, backs, 16, 64)
    assert len(backs) == 6 and baked.sum() / traced.sum() > 0.77, baked / traced


def test_thin_ball_holds_single_and_multiple_scattering_in_two_lobes(folder):
    # A thin ball (voxels of optical depth 1, all traced; omega 0.999, g 0.5) from the sun's side, across and
    # against the sun. Its source is half the sun's single scattering, HG(0.5) about the sun's travel, and half
    # light scattered more often, nearly isotropic: one lobe of the mixture's first moment (HG(0.3)) is 10 %
    # too dark from the sun's side and from above (measured -10 %, +5 %, -8 %, -10 %; docs/bake.md), the peaked
    # lobe holding the beam's single scattering beside the broad one gets every view within 6 % (measured -1 %,
    # +0 %, -5 %, -1 % against the suite's 16384 paths).
    result = baked_against_reference(folder, "ball_thin", 2048)
    assert all(abs(b) < 0.07 for b in result["view_bias"]), result["view_bias"]


def test_sun_lit_ball_is_right_where_the_surface_model_can_hold(folder):
    # The issue's ball (omega 0.98, g 0.85, 1 cm voxels of optical depth 10), seen from the sun's side and
    # across the terminator: within 12 % per view (measured +5.6 %, -11.2 % against these 1024 paths; -11 % against
    # the suite's 16384). With the returned sun in the linear sun lobe alone it was +5.3 %, -8.6 %: the sun's sharply
    # forward return, now the peaked lobe, was partly shown sideways (-10.3 % with that alone; the traced fringe's
    # two lobes fitted to four moments, Method 3, another -0.9 points). Across the terminator the lit face is
    # -19.8 % (then -17.8 %) where the exact half-space at each pixel's point is -23.1 %
    # (bench/bake_halfspace.py): what is missing there is light crossing the curved snow, not the surface's
    # angular shape. Seen against the sun: test_sun_returned_at_grazing_incidence_lights_the_rim_seen_against_the_sun.
    result = baked_against_reference(folder, "ball_issue", 1024, [(0, 0), (90, 0)])
    assert all(abs(b) < 0.12 for b in result["view_bias"]), result["view_bias"]


def test_sun_returned_at_grazing_incidence_lights_the_rim_seen_against_the_sun(folder):
    # The issue's ball (omega 0.98, g 0.85) and the absorbing grey one (omega 0.9, g 0.6) seen against the sun, against the core's
    # Monte Carlo: the lit top's rim is the view's brightest part, where a half-space returns grazing sun sharply
    # forwards (R / A 13-16 at grazing forward exit for mu0 = 0.28; bench/bake_halfspace.py). With the returned sun
    # in the surface's linear sun lobe the view is 48.2 % and 44.4 % too dark (measured against these 1024 paths;
    # 48 % and 44 % against the suite's); with the share of it that returns sharply forwards as the surface voxels'
    # peaked lobe (SunPeak) 39.8 % and 32.9 % (39 %, 32 %; docs/bake.md, Accuracy). What is left is mostly the
    # shadowed side lit by light crossing the curved snow, and the rim's density ramp.
    for name, low in (("ball_issue", -0.44), ("ball_grey", -0.38)):
        result = baked_against_reference(folder, name, 1024, [(180, 0)])
        assert low < result["view_bias"][0] < 0.10, (name, result["view_bias"])


def test_ramp_in_front_of_a_lit_rim_carries_the_returned_grazing_sun(folder):
    # Seen against the sun a thick ball's top row becomes opaque in the density ramp on the camera's side of
    # the top, whose own surface voxels take the sun at grazing incidence (mu0 0-0.2) and hold little of the
    # sun's forward return, while the core's Monte Carlo finds the lit top's forward return travelling through
    # that ramp (its source there 0.3-0.4 W/m^2/sr against the bake's 0.15-0.2 on ball_issue). With the ramp's
    # sunlit voxels carrying the peaked lobes of the smooth surface voxels within two voxels whose peak travels
    # towards them (bake_grid_values.cpp, forwardPeakThrough), against these 1024 paths (noise 5.0 %, 3.1 %, 2.5 %):
    # ball_issue view -40.1 % -> -32.0 %; ball_grey (omega 0.9, g 0.6) view -32.9 % -> -24.1 %, its worst block -61 % ->
    # -48 %; ball_clean (omega 1 - 1e-7, g 0.85, 5 mm voxels) worst block -60 % -> -48 % (docs/bake.md, Accuracy).
    # Then ball_issue's top row became opaque in the one-voxel density ramp on the camera's side of the lit top
    # (branch backlit: 0.63 of the view's missing 1.02 there), where the sun arrives through the top's own snow; the
    # sun's transmittance that weighs the carried peaks is delta-scaled by the forward share omega g^2
    # (delta-Eddington; branch seen-sun), and where more, so is the peaks' own way through the ramp from their
    # voxel's boundary (rampCrossing; branch lit-top): against these 1024 paths (median block noise 7.5 %: the view's
    # sum of 52 blocks about 1 %) -26.6 % with neither, -20.5 % with the sun's alone, -17.0 % with both (the suite's
    # 16384 paths the same to 0.1 point; docs/bake.md, Accuracy; docs/benchmarks.md, seen-sun and lit-top); the bound
    # lies midway, 1.7 points (beyond the sum's noise) from each. The view from the sun's side stays +1.1 %.
    issue = baked_against_reference(folder, "ball_issue", 1024, [(180, 0), (0, 0)])
    assert issue["view_bias"][0] > -0.1875, issue["view_bias"]
    assert abs(issue["view_bias"][1]) < 0.05, issue["view_bias"]
    grey = baked_against_reference(folder, "ball_grey", 1024, [(180, 0)])
    assert grey["view_bias"][0] > -0.28, grey["view_bias"]
    # The worst block here is no longer the top row's: since lit-top it is the equator's rim past the terminator,
    # too bright (main +55.0 % against these 1024 paths; +55.4 % since the ramp's own single scattering, beamsInRamp,
    # branch ball-rims: docs/benchmarks.md). Not a double count of the surface model's sun: with beamsInRamp gated at
    # mu0 < 0 (voxels whose surfaces take no sun at all) the block reads +55.4 % too; the ramp there scatters the sun
    # the surfaces lack (the terminator test below bounds it from below), on a rim over-bright already (its baked
    # radiance 1.5-2.7x the Monte Carlo's along the ray on main). This block was over-bright, a
    # known error: +55.4 % before and +57.9 % since the ramp's own sun is added to the carried peaks beside thick
    # convex snow (branch rim-forward: the top rim's light, whose gains elsewhere outweigh it; tapering that addition
    # with the carriers' mu0 did not recover the block, docs/benchmarks.md, mends-rim52). Its cause was
    # forwardPeakThrough's sun share taken at an air voxel's centre (T = 1) beside carriers well past the terminator:
    # averaged over the voxel's hat (branch grey-rims) the view's worst block reads +33.1 % (now the second row's
    # outer blocks; the rim's about +25 %); the bound lies midway between that and +57.9 %.
    assert grey["worst"] < 0.45, grey["worst_signed"]
    clean = baked_against_reference(folder, "ball_clean", 1024, [(180, 0)])
    assert clean["worst"] < 0.55, clean["worst_signed"]


def test_absorbing_balls_under_a_uniform_sky_return_what_a_half_space_returns(folder):
    # The grey ball (omega 0.9, g 0.6) and the issue's (omega 0.98, g 0.85) under a uniform sky of 1 alone, from the
    # side, above and below, against the core's Monte Carlo (1024 paths; noise 2.6 % and 1.8 % per block, about
    # 0.2 % on a view's sum). The diffusion returns less diffuse light than the snow does where it absorbs: on a
    # half-space (1 - 2 kappa D) / (1 + 2 kappa D) = 0.300 and 0.429 against the exact spherical albedo 0.330 and
    # 0.447 (the sun lobe's Monte Carlo table, sun_lobe.h sphericalAlbedo). Missing that, the views were -5.6, -5.2,
    # -6.0 % and -9.5, -9.2, -9.1 % (bias -5.6 %, -9.2 %); with the difference leaving in the escape function's
    # shape +1.8, +2.1, +1.4 % and -6.6, -6.2, -6.1 % (bias +1.8 %, -6.3 %: the issue's ball keeps a curved body's
    # own error, docs/bake.md, Accuracy).
    for name, low, high in (("ball_grey", -0.04, 0.04), ("ball_issue", -0.08, 0.0)):
        c = case(name)
        c.sun, c.sky, c.samples, c.views = 0.0, 1.0, 1024, [(0, 0), (0, 60), (0, -60)]
        result = bake_suite.run_case(c, folder, cache=None)
        assert low < result["bias"] < high, (name, result["bias"], result["view_bias"])


def test_sunward_faces_of_absorbing_balls_return_what_a_half_space_returns(folder):
    # The issue's ball (omega 0.98, g 0.85) and the grey one (omega 0.9, g 0.6) seen from the sun's side and from
    # above, against the core's Monte Carlo (1024 paths; noise 8.2 % and 3.4 % per block). The voxel scheme returns
    # of a beam at steep incidence more than a half-space of the snow does, at grazing less (0.387 against 0.353,
    # the sun lobe table's plane albedo, at mu0 1 for the issue's snow: bake_diffusion_system.cpp, schemeBeamAlbedo).
    # Without the difference (main with the diffuse step): bias +7.1 % and +8.7 %, the grey ball's mean 14.5 %; with it
    # leaving in the escape function's shape (surfaceLight) +6.2 % and +7.4 %, 12.0 %. Subtracting the 1D diffusion's
    # a' / ((1 + 3 kappa D mu0) (1 + 2 kappa D)) instead gave +3.7 %, +5.0 %, 10.7 %, but flat slabs 9 % too dark
    # (test_flat_absorbing_slab_returns_a_half_space_albedo_of_the_sun; docs/bake.md, Accuracy).
    issue = baked_against_reference(folder, "ball_issue", 1024, [(0, 0), (0, 60)])
    assert abs(issue["bias"]) < 0.07, issue["view_bias"]
    grey = baked_against_reference(folder, "ball_grey", 1024, [(0, 0), (0, 60)])
    assert abs(grey["bias"]) < 0.08 and grey["mean"] < 0.125, (grey["bias"], grey["mean"])


def test_light_flowing_along_a_ball_surface_leaves_leaning_the_way_it_flows(folder):
    # The issue's ball (omega 0.98, g 0.85) and the grey one (omega 0.9, g 0.6) from the sun's side, from above and
    # against the sun, against the core's Monte Carlo (1024 paths). The diffusion's radiance (phi + 3 F . w) / 4 pi
    # holds the flux along the surface, which the escape function (the flux across it) does not: on the sunward face
    # the fluence falls away from the point under the sun, past the terminator away from the lit side, and the light
    # leaves leaning that way (bake_surface_light.cpp, surfaceLight: 3 F_t / phi added to the exit form, no exitance
    # moved). Without it (main d0f6311) the views read +5.5, +6.9, -30.2 % and +7.1, +7.8, -19.1 %; with it +1.5, +2.6,
    # -27.3 % and +3.8, +4.1, -17.0 % (docs/bake.md, Accuracy: the terminator).
    for name, against in (("ball_issue", -0.29), ("ball_grey", -0.18)):
        result = baked_against_reference(folder, name, 1024, [(0, 0), (0, 60), (180, 0)])
        towards, above, behind = result["view_bias"]
        assert -0.05 < towards < 0.05 and -0.05 < above < 0.05 and behind > against, (name, result["view_bias"])


def sun_leaving_along_the_normal(folder, name, angles, samples=4096):
    """The suite's ball `name` under its sun alone: the radiance leaving along the normal at angles psi from the
    sunward pole (bench/bake_terminator.py; 90: the terminator), baked and by the core's Monte Carlo (channel G)."""
    c = case(name)
    origins, directions, labels = bake_terminator.rays(c, angles)
    normal = [k for k, (_, exit_name, _) in enumerate(labels) if exit_name == "normal"]
    origins, directions = origins[normal], directions[normal]
    path = sun_alone_baked(folder, name)
    reference, _ = firncore.monte_carlo_radiance(path, c.optics, origins, directions, samples=samples, seed=7,
                                                 suns=c.suns(), sky=None)
    return firncore.render_baked(path, c.optics, origins, directions)[:, 1], reference[:, 1]


def test_sun_entering_before_the_terminator_leaves_past_it(folder):
    # The sun entering a ball at grazing incidence just before the terminator leaves downstream: a half-space returns
    # a beam 0.6-0.7 transport mean free paths further along its travel, +-0.8-1.3 (bench/halfspace_displacement.py),
    # and on a ball the light crosses the terminator so. The half-space model returned it at the patch it entered; the
    # light it returns at once leaves downstream by that displacement (bake_sun_downstream.cpp, sunLeavingDownstream).
    # The sun's radiance along the normal at psi 85, 90, 95, 100 degrees, summed, baked over the core's Monte Carlo
    # (4096 paths, seed 7; seed 11: 0.62, 0.34 -> 0.75, 0.47): main 9719e11 returned 0.57 (ball_issue) and 0.32
    # (ball_grey), that branch 0.69 and 0.44; main 844cd72 (with the ramp's inflow at 95-100) 0.90 and 0.64 (seed 11:
    # 0.98, 0.68) (docs/bake.md, Accuracy: the terminator).
    for name, least in (("ball_issue", 0.63), ("ball_grey", 0.39)):
        baked, reference = sun_leaving_along_the_normal(folder, name, [85, 90, 95, 100])
        assert baked.sum() / reference.sum() > least, (name, baked / reference)


def test_sun_returned_at_once_stays_on_the_lit_side_of_a_staircase_terminator(folder):
    # ball_issue's +y plateau of 1 cm voxels, seen from the side (rays along -y): the sun (from +x, 30 degrees up) runs
    # parallel to its air faces and the smooth sphere's terminator crosses it. The sun a patch returns at once follows
    # the sun's cosine, which changes within a voxel there; averaged over the whole 3^3 block before it moved
    # downstream, the plateau's voxels past the terminator took their lit neighbours' (bake_sun_downstream.cpp,
    # kAtOnceReach). The sun alone at x -1 to -0.25 cm from the centre, 0.5 and 1.5 cm up
    # (bench/plateau_sun_profile.py), summed, baked over the core's Monte Carlo (4096 paths, seed 37; the sum's standard
    # error 3.7 %, though three seeds spread 1 %): main b8f757d 1.165, this 1.091 (seeds 11 and 5: 1.149, 1.154 ->
    # 1.075, 1.080; docs/benchmarks.md, plateau-sun). Since the ramp's single scattering takes the delta-scaled sun
    # where the surface takes it at grazing (lead-92) 1.119: the row 1.5 cm up, too dark, 0.77-0.89 -> 0.80-0.92 of the
    # truth; the row 0.5 cm up, past the terminator, where the at-once light leaked, the same to three digits.
    c = case("ball_issue")
    path = os.path.join(folder, "plateau.vdb")
    bake_suite.write_density(path, c.density, c.voxel)
    past = (plateau_sun_profile.OFFSETS >= -1.0) & (plateau_sun_profile.OFFSETS <= -0.25)  # cm
    rows = [plateau_sun_profile.rays(c, row) for row in (0.5, 1.5)]
    origins = np.concatenate([o[past] for o, _ in rows])
    directions = np.concatenate([d[past] for _, d in rows])
    reference, _ = firncore.monte_carlo_radiance(path, c.optics, origins, directions, suns=c.suns(), samples=4096,
                                                 seed=37)
    firncore.bake(path, c.optics, quality="FINAL", suns=c.suns(), sky=None)
    baked = firncore.render_baked(path, c.optics, origins, directions)
    assert baked[:, 1].sum() / reference[:, 1].sum() < 1.14, baked[:, 1] / reference[:, 1]


def test_sun_grazing_the_ramp_past_the_terminator_feeds_the_outer_node(folder):
    # Past the terminator the sun grazes through the ball's density ramp (to acos(R / (R + h/2)), 20-25 degrees on
    # these balls) and what the ramp scatters inwards feeds the skin: the core's Monte Carlo's net flux at the outer
    # node points inwards there (bench/skin_flux.py). No beam enters through a patch facing away from the sun, so the
    # diffusion's outer node held 0.26-0.41 of the truth's fluence at 95-115 degrees (ball_issue); the ramp's inflow
    # (bake_diffusion_system.cpp, rampInflow) gives 0.67-1.01. The sun's radiance along the normal at psi 100, 105,
    # 110 degrees, summed, baked over the core's Monte Carlo (4096 paths, seed 7; seed 11: 0.86, 0.91): main 2c528ec
    # 0.55 (ball_issue) and 0.70 (ball_grey), this 0.82 and 0.87 (docs/benchmarks.md, limb-skin). No brighter than the
    # truth: twice the inflow (all the ramp's scattering into the node) reads 1.09 and 1.04 (seed 11: 1.15, 1.09).
    for name, least in (("ball_issue", 0.70), ("ball_grey", 0.78)):
        baked, reference = sun_leaving_along_the_normal(folder, name, [100, 105, 110])
        assert least < baked.sum() / reference.sum() < 1.0, (name, baked / reference)


def test_large_area_lamp_near_a_ball_lights_the_patches_that_see_part_of_it(folder):
    # ball_grey under a 40 x 40 cm rectangle 10 cm from its surface (bench/lamp_terminator.py, no sky): the patches to
    # about 110 degrees past the lamp centre's terminator see part of the lamp. Lit as one beam from its centre
    # (main 8ad7c9a) the four views' render read -31 % against the core's Monte Carlo (the suite's views; 16384 paths),
    # the blocks past that terminator (cosine to the centre -0.5-0) -44 to -68 %; in pieces at most twice as wide as
    # their distance to the snow (lamps.h, lampPieces) -6 %, those blocks -6 to -21 % (docs/benchmarks.md, ramp-lamps,
    # review-mends49). These 1024 paths: main -30.0 %, past -43 to -67 %; in pieces -5.7 %, past -5 to -20 %; with the
    # patches' way to the lamp from their surface (lamp-near) -9.7 %, past -9 to -27 %.
    result = lamp_row(folder, "area")
    past = [cells[2] for cells in result["bands"]]  # (baked / Monte Carlo - 1, blocks) per view
    assert all(blocks > 0 for _, blocks in past), past
    assert -0.15 < result["bias"] < 0.1 and min(r for r, _ in past) > -0.35, (result["bias"], past)


def test_point_lamp_near_a_ball_lights_its_patches_from_their_surface(folder):
    # ball_grey under a point lamp 10 cm (10 voxels) from its surface (bench/lamp_terminator.py, no sky): its way
    # and so the cosine it enters a patch at vary across a voxel. Taken from the voxel centres (main 02f891e), half a
    # voxel under the patches, the lamp stood higher over every patch and the patches past its terminator took its
    # light: the blocks past it seen against the lamp read +56 % against the core's Monte Carlo (16384 paths; the sun
    # at the lamp's direction from each block's terminator +37 % there); from the patches' surface (incident_light.h,
    # patchSurface) +22 % (docs/benchmarks.md, lamp-near). These 1024 paths: main +59 %, the bias over the views
    # -2.2 %; the patches' surface +24 %, -8.2 %.
    result = lamp_row(folder, "point")
    past = [cells[2] for cells in result["bands"]]  # (baked / Monte Carlo - 1, blocks) per view
    assert all(blocks > 0 for _, blocks in past), past
    assert max(r for r, _ in past) < 0.4 and -0.15 < result["bias"] < 0.05, (result["bias"], past)


def test_lamps_scatter_their_light_in_the_ramp_beside_grazing_patches(folder):
    # ball_grey under bench/lamp_terminator.py's lamps, 1024 paths (the suite's views, no sky). The ramp voxels beside
    # patches a beam meets grazingly scatter it once (bake_grid_values.cpp, beamsInRamp). Lamps once got none, and an
    # area lamp's 16 pieces none where one piece met the patch at mu0 >= 0.4: main 72c1a45 read the area lamp -11.7 %,
    # -27.8 % seen against it, the point lamp -10.6 %; each beam on its own, the area lamp's pieces grazing or past
    # their terminator, the point lamp on its lit side only (0 <= mu0): -5.2 %, -6.9 %, -7.4 %. The upper bound 0.4 on
    # the point lamp's view against it catches the ramp given past its terminator too (+82 % against 16384-path
    # references; this view reads +27.7 % here, main +19.5 %) (docs/benchmarks.md, lamp-shell, lamp-ramp).
    # Since a small ball's carried light divides (skin_ring.h, carriedSunSpread; stop 91) this absorbing ball reads
    # about 3 points darker under every light (16384-path references, bench/lamp_terminator.py: the sun -4.6 ->
    # -7.3 %, the point lamp -7.6 -> -10.4 %, the area lamp -5.7 -> -8.5 %; here the point lamp -10.2 %): the point
    # lamp's bias no longer tells a lost ramp light, its view against it and the area lamp's still do. Since its carried
    # light divides by (1 + kappa d)^3/4 (stop 92) the point lamp reads -11.8 % (16384 paths; -11.5 % here), the area
    # lamp -8.5 % as before (-8.05 % here): the area lamp's bound -8 -> -10 %, which its lost ramp light (-11.7 %)
    # still fails (docs/benchmarks.md, lead-92).
    area = lamp_row(folder, "area")
    point = lamp_row(folder, "point")
    against = 2  # view (180, 0)
    assert -0.10 < area["bias"] < 0.05 and area["views"][against] > -0.18, (area["bias"], area["views"])
    assert -0.12 < point["bias"] < 0.05 and point["views"][against] < 0.4, (point["bias"], point["views"])


def test_area_lamp_pieces_ramp_light_stands_for_their_own_return_alone_seen_from_above(folder):
    # A flat slab of ball_grey's snow under a 60 x 60 cm square lamp 5 cm over its top (bench/lamp_slab_pieces.py,
    # 1024 paths, five views): the top takes some of its pieces (mu0 >= 0.4) and meets others grazingly, whose light
    # the ramp scatters (bake_grid_values.cpp, beamsInRamp). The ramp voxel's carried peak holds every piece's return,
    # 84 % of it the grazing pieces'. Replacing it by their ramp light where larger dropped the taken pieces' return
    # (-6.2 % against these paths); adding the ramp light to it counted the grazing pieces' return twice, seen from
    # above +4.8 % (-2.1 % overall; a sun at 20 degrees so +14.7 % where compared -0.8 %). Set against their own return
    # alone (SurfaceLight::rampPeak0), the taken pieces' kept: from above +1.3 %, overall -5.8 % (4096 paths: +4.5 ->
    # +1.0 %, -3.1 -> -6.7 %: the side views' deficit is the lowest pieces', as a sun at 10 degrees reads -28 %;
    # docs/benchmarks.md, area-pieces, peak-split).
    bias, views, _ = lamp_slab_pieces.measure(folder, "grey", "square", samples=1024)
    above = 4  # view (0, 90)
    assert -0.08 < bias < 0.0 and abs(views[above]) < 0.03, (bias, views)


def test_a_low_sun_over_flat_snow_enters_past_the_surfaces_own_density_ramp(folder):
    # The grey slab of lamp_slab_pieces.py under a sun 5 and 10 degrees up (1024 paths, five views). A patch took its
    # sun from at most 3 times the ramp's height along the light (patchOutsideAlong): below mu0 1/3 the ray started
    # inside the slab's own trilinear ramp and crossed it on a long chord, so the flat top lost its sun (-69.7 % and
    # -27.8 % against 4096 paths, -87.5 % at 3 degrees; worse the denser the voxel: 20 per voxel -74 % at 10 degrees).
    # From past the ramp +24.2 % and +16.5 % (the tables' overshoot at grazing, left; docs/benchmarks.md, grazing-sun).
    for elevation, bound in ((5, 0.3), (10, 0.2)):
        bias, views, _ = lamp_slab_pieces.measure(folder, "grey", f"sun{elevation}", samples=1024)
        assert abs(bias) < bound, (elevation, bias, views)


def point_lamp_over_a_flat_slab(folder, omega, g, tau, height):
    """The render's bias against the core's Monte Carlo (2048 paths): a flat slab 40 x 40 x 6 voxels of 1 cm of the
    snow (tau per voxel), a point lamp `height` m over its top's middle, seen from 45 degrees within 11 cm of the point
    under it."""
    layers, h = 6, 0.01
    density = bake_suite.slab(40, layers) * 100.0
    optics = firncore.VolumeOptics(tau / h / 100.0, (omega,) * 3, g)
    path = os.path.join(folder, "lamp_slab.vdb")
    bake_suite.write_density(path, density, h)
    top = bake_suite.slab_top(density, layers, h)
    lamp = firncore.Lamp("POINT", tuple(top + [0.0, 0.0, height]), (1.0,) * 3)
    view = np.array([0.0, -math.sqrt(0.5), -math.sqrt(0.5)])
    points = [top + r * np.array([math.cos(a), math.sin(a), 0.0])
              for r in np.arange(12) * h for a in np.arange(8) * math.pi / 4]
    origins, directions = np.array(points) - 0.5 * view, np.tile(view, (len(points), 1))
    reference, _ = firncore.monte_carlo_radiance(path, optics, origins, directions, lamps=[lamp], samples=2048, seed=11)
    firncore.bake(path, optics, lamps=[lamp], quality="FINAL", seed=0)
    baked = firncore.render_baked(path, optics, origins, directions)
    return baked[:, 1].sum() / reference[:, 1].sum() - 1.0


def test_point_lamp_over_a_flat_slab_spreads_its_beam_through_the_voxels_side_faces(folder):
    # ball_issue's snow (omega 0.98, g 0.85, tau 10 per voxel), the lamp 10 cm up. The beam spreads: through
    # a voxel's side faces it leaves outwards. Taken at the voxel centre, the way to the lamp made those faces'
    # cosines those of a beam parallel to the centre's ray, so the spread counted as scattered: +8.0 % against the
    # core's Monte Carlo (these 2048 paths), +11 to +14 % within 2 cm of the point under the lamp; the way from each
    # face's own centre (bake_diffusion_system.cpp) -0.1 %, +1 to +4 % (docs/benchmarks.md, lamp-faces; +2.0 % since
    # grey-lamps).
    bias = point_lamp_over_a_flat_slab(folder, 0.98, 0.85, 10.0, 0.1)
    assert abs(bias) < 0.04, bias


def test_point_lamp_close_over_grey_snow_returns_what_its_spread_beam_lets_in(folder):
    # ball_grey's snow (omega 0.9, g 0.6, tau 5 per voxel), the lamp 3 cm up: the beam's spread through the top
    # voxels' side faces (lamp-faces) goes to the neighbours' nodes, not escaping at once; the half-space correction
    # (bake_surface_light.cpp) must count it in what the voxel scheme returns (schemeBeamAlbedo's spreadOut), or the
    # grey snow reads -8.3 % (-13 % within 2 cm of the point under the lamp); with it -3.2 % (docs/benchmarks.md,
    # grey-lamps).
    bias = point_lamp_over_a_flat_slab(folder, 0.9, 0.6, 5.0, 0.03)
    assert abs(bias) < 0.06, bias


@pytest.mark.parametrize("omega, g, tau_per_voxel", bake_flat_slab.SNOWS)
def test_flat_absorbing_slab_returns_a_half_space_albedo_of_the_sun(folder, omega, g, tau_per_voxel):
    # The sun's half-space correction (bake_surface_light.cpp, surfaceLight) subtracts what the voxel scheme itself
    # returns of a beam (schemeBeamAlbedo: 0.266 overhead for omega 0.9, g 0.6 at tau 5 per voxel) from the sun lobe
    # table's albedo. A wide flat slab under sun alone, its baked radiance integrated over the hemisphere
    # (bench/bake_flat_slab.py); oracle: the core's 1D Monte Carlo of the half-space (slab_monte_carlo, tau inf).
    # Without the correction the slabs returned +11.6 %, -9.8 % (omega 0.9; sun at 90 and 30 deg) and +10.3 %,
    # -6.6 % (omega 0.98); subtracting the 1D diffusion's a' / ((1 + 3 kappa D mu0) (1 + 2 kappa D)) instead (0.281
    # overhead) -3.5 %, -8.9 % and -1.3 %, -5.2 %; so +2.8 %, +0.6 % and +0.6 %, +0.9 %: the table's own error, its
    # albedo 0.245 at mu0 1 where this Monte Carlo finds 0.2376 (trilinear in y).
    for elevation in bake_flat_slab.ELEVATIONS:
        exact, _ = bake_flat_slab.half_space_albedo(omega, g, elevation)
        baked = bake_flat_slab.baked_albedo(folder, omega, g, tau_per_voxel, elevation)
        assert baked == pytest.approx(exact, rel=0.04), (elevation, baked, exact)


def test_forward_light_crossing_a_ball_leaves_its_far_side(folder):
    # A 5 cm ball (voxels of optical depth 4, omega 0.999, g 0.9) seen against the sun: the sun's forward-
    # scattered beam crosses it and leaves through the far side's surface (bake_surface_light.cpp, crossing beams).
    # Without that light the view is 30 % too dark against the core's Monte Carlo (these 1024 paths; 31 % against the
    # suite's 4096), with it 18 % (20 %; docs/bake.md, Accuracy). Guarded at 25 %.
    result = baked_against_reference(folder, "ball_forward", 1024, [(180, 0)])
    assert -0.25 < result["view_bias"][0] < 0.05


def test_ball_thin_in_transport_mean_free_paths_is_light_traced_whole(folder):
    # A 5 cm ball of voxels of optical depth 4 (omega 0.999, g 0.9): 40 optical depths across but 4 transport mean
    # free paths (sigma_tr h 0.4), 672 voxels. Diffused (all but its 120 thinnest fringe voxels) it read 14.9 %
    # per block against the suite's 16384-path reference (worst +62 %; rays through its fringe alone 22.7 %, the
    # inside +-20 % across the sun); light traced whole, as a piece of at most 64 in (sigma_tr h)^3 summed
    # (bake_thin_snow.cpp, thinVoxels), 8.0 % (worst -31 %; docs/bake.md, Accuracy). Against these 4096 paths (noise
    # about 6.1 % per block): diffused 15.3 % (120 voxels traced), light traced whole 8.8 %.
    result = baked_against_reference(folder, "ball_forward", 4096)
    assert result["traced"] == int((case("ball_forward").density > 0).sum())
    assert result["mean"] < 0.12, result["mean"]


def test_layer_thin_in_transport_mean_free_paths_is_traced_whole(folder):
    # The suite's slab_thin: 24 x 24 x 3 voxels of optical depth 2 (omega 0.99, g 0.6; sigma_tr h 0.81): 2.4
    # transport mean free paths thick, 1728 voxels, too wide for the pieces traced whole by their volume. A
    # diffusion across three voxels has no inside: diffused it read 8.0 % per block against the suite's 16384
    # paths (worst -34 %, bias -2.7 %, seen from above -8 %); traced whole, as a piece no voxel of which lies 2.5
    # transport mean free paths deep (bake_thin_snow.cpp, axisDepth), 6.2 % (+17 %, +0.9 %, -3 %). Against these 1024
    # paths (noise 3.8 % per block): diffused 8.4 %, from above -7.7 %; traced whole 6.7 %, -2.5 % (since slab-thin,
    # its one-sided faces gathered, 5.1 %: the test below).
    result = baked_against_reference(folder, "slab_thin", 1024)
    assert result["traced"] == int((case("slab_thin").density > 0).sum())
    assert result["mean"] < 0.075, result["mean"]
    assert abs(result["view_bias"][0]) < 0.05, result["view_bias"]


def test_layer_traced_whole_shows_cameras_below_its_underside(folder):
    # slab_thin seen from below: light traced whole, its lowest voxels' mean source (2 optical depths, the sun-lit
    # top's forward light in it) is brighter than the first optical depth of their lower face, which a camera below
    # sees: against the suite's 16384 paths, seeds 0-2, (0, -60) +8.2 %, 8.4 % per block (docs/benchmarks.md,
    # slab-thin). Since branch slab-thin a traced layer's faces open to air on one side gather their own source
    # (bake_traced_voxels.cpp, addFaceSources): +3 %, 3.9 % per block. Against these 1024 paths (noise 3.8 % per
    # block): main 6.7 %, (0, -60) +8.1 %; since slab-thin 5.1 %, +2.8 %.
    result = baked_against_reference(folder, "slab_thin", 1024)
    assert abs(result["view_bias"][2]) < 0.05, result["view_bias"]
    assert result["mean"] < 0.06, result["mean"]


def test_layer_thin_in_transport_mean_free_paths_over_the_ground_is_traced_whole_too(folder):
    # slab_thin's layer 1 cm over a grey ground (albedo 0.5), seen from above. Until branch trace-quality any occluder
    # kept light tracing's two other uses off (transport-thin pieces traced whole, forward snow at the gathering's
    # cost: measured without occluders only), and the diffusion took the layer: against 4096 paths per block, seeds
    # 0-2, 9.0, 9.2, 9.0 % per block, from (0, 60) -9 % each; traced whole 5.9, 5.7, 6.0 %, -2, -1, -2 % (docs/bake.md
    # Method 3). Against these 1024 paths (noise 3.6 % per block): diffused 9.0 %, from above -8.5 %; traced whole
    # 6.2 %, -1.8 %.
    c = case("slab_thin")
    c.occluders = [bake_suite.plate(-1.0, 2.0, -1.0, 2.0, 0.005, (0.5, 0.5, 0.5))]  # the layer's bottom at 0.015 m
    c.views, c.samples = [(0, 60), (90, 75), (180, 50)], 1024
    result = bake_suite.run_case(c, folder, cache=None)
    assert result["traced"] == int((c.density > 0).sum())
    assert abs(result["view_bias"][0]) < 0.05, result["view_bias"]
    assert result["mean"] < 0.075, result["mean"]


def test_layer_of_optically_thick_voxels_keeps_the_diffusion(folder):
    # slab_thin's layer with voxels of optical depth 3 (omega 0.99, g 0.6; sigma_tr h 1.2, 1.8 transport mean free
    # paths deep): a voxel's mean source is no longer what a camera sees of its first optical depth. Against 4096
    # paths per block: diffused 6.3 % (views -4, -2, +4, -5 %), traced whole 10.4 % (-8, -8, +11, +3 %;
    # bake_thin_snow.cpp, kTracedLayerOpticalDepth). Against these 1024 paths (noise 3.7 %): diffused 7.0 %, traced
    # whole 11.2 %.
    c = bake_suite.Case("slab_tau3", "", bake_suite.slab(24, 3) * 100, 0.01, 300.0, 100.0, (0.99,) * 3, 0.6,
                        views=case("slab_thin").views, samples=1024)
    result = bake_suite.run_case(c, folder, cache=None)
    assert result["traced"] == 0
    assert result["mean"] < 0.085, result["mean"]


@pytest.mark.parametrize("width, layers", [(16, 1), (10, 3)])
def test_small_layer_of_dense_snow_on_the_ground_keeps_the_diffusion(folder, width, layers):
    # bench/snow_on_ground_bench.py's "flat 1" and --one-voxel's 10x10x3: voxels of bumpy_plate's snow (tau 15
    # per voxel, omega 0.999, g 0.7; sigma_tr h 4.5) on a grey ground (albedo 0.5) under the sun 30 degrees high and
    # the sky. Oracle: the core's Monte Carlo (1024 paths per block, noise 4.1-4.5 % per block). Their 256 and 300
    # voxels made small pieces traced whole, and a traced voxel's mean source is not what a camera sees of its first
    # optical depth: 41.2 % per block, bias -42.3 %; 23.4 %, -20.0 %. Diffused (bake_thin_snow.cpp, pieceAround: a dense
    # layer with no inside, or wide in transport mean free paths, whose voxels each face the air on one side only)
    # 11.1 %, +1.6 %; 8.6 %, +0.3 %.
    h = 0.01
    ground = bake_suite.plate(-1.0, 2.0, -1.0, 2.0, 1.5 * h, (0.5, 0.5, 0.5))  # between the empty row and the snow
    c = bake_suite.Case(f"flat_{width}_{layers}", "", bake_suite.slab(width, layers) * 300.0, h, 1500.0, 300.0,
                        (0.999,) * 3, 0.7, views=[(0, 60), (180, 50), (90, 70)], occluders=[ground], samples=1024)
    result = bake_suite.run_case(c, folder, cache=None)
    assert result["traced"] == 0
    assert abs(result["bias"]) < 0.08, result["bias"]
    assert result["mean"] < 0.16, result["mean"]


def test_floating_layer_one_voxel_thick_shows_each_faces_first_optical_depth(folder):
    # bench/snow_on_ground_bench.py --float's 16x16x1 at tau 15 seen from above: a layer one voxel thick of
    # bumpy_plate's snow (omega 0.999, g 0.7) with air on both sides, under the sun 30 degrees high and the sky.
    # Its 256 voxels are traced (a small piece, two-sided), and a traced voxel's mean source, which the air on both
    # sides carried, is not what a camera sees of the face it looks at: the views from above read 33.3 % per block,
    # bias -34.4 %. With each air neighbour carrying its face's own source (bake_traced_voxels.cpp, addFaceSources):
    # 9.1 %, -4.1 %. Oracle: the core's Monte Carlo, 1024 paths per block (noise 4.3 % per block; over the 192 blocks
    # the bias's noise is about 0.3 %).
    c = bake_suite.Case("float_16x16x1", "", bake_suite.slab(16, 1) * 300.0, 0.01, 1500.0, 300.0, (0.999,) * 3, 0.7,
                        views=[(0, 60), (180, 50), (90, 70)], samples=1024)
    result = bake_suite.run_case(c, folder, cache=None)
    assert result["traced"] == 256
    assert abs(result["bias"]) < 0.15, result["bias"]
    assert result["mean"] < 0.16, result["mean"]


def test_floating_layer_one_voxel_thick_shows_its_underside_what_it_sees(folder):
    # The same layer seen from below (views (0, -60), (180, -50), (90, -70)). A camera ray from below collides about
    # 30 % of its weight within the voxel's own trilinear hat, whose value was the voxel's mean source, and the mean
    # holds the sun-lit top's forward light: towards a camera below it was 46 % brighter than what the voxel shows
    # there, so the underside read 19.2 % per block, bias +16.3 % (branch float-voxel). With the voxel's own value
    # what it shows each face's cameras, split from its air neighbours' by the hat (bake_traced_voxels.cpp,
    # addFaceSources; monte_carlo.h, faceSourceIn): 10.7 %, +3.0 %. Oracle: the core's Monte Carlo, 1024 paths per
    # block (noise 4.9 % per block; the bias's about 0.4 %).
    c = bake_suite.Case("float_16x16x1_below", "", bake_suite.slab(16, 1) * 300.0, 0.01, 1500.0, 300.0,
                        (0.999,) * 3, 0.7, views=[(0, -60), (180, -50), (90, -70)], samples=1024)
    result = bake_suite.run_case(c, folder, cache=None)
    assert result["traced"] == 256
    assert abs(result["bias"]) < 0.08, result["bias"]
    assert result["mean"] < 0.14, result["mean"]


def test_thin_snow_too_costly_to_gather_per_voxel_is_light_traced(tmp_vdb):
    # A 40 cm cloud of voxels of optical depth 1.4 that hardly absorbs: each of its voxels is thin, but light
    # in it scatters hundreds of times (28 mean free paths to its edge), beyond the budget of gathering per voxel.
    # The bake measures that on a few voxels first and traces the light from the sky forwards instead, its paths
    # serving every voxel they cross, within the same budget (docs/bake.md Method 3). Under a uniform sky of 1 a
    # conservative medium's radiance is 1 everywhere: seen from above, the cloud's is 1 (before light tracing the
    # diffusion took the cloud: 0.5 to 1 was all this test could ask).
    density = bake_suite.ball(0.2, 0.01) * 100.0
    bake_suite.write_density(tmp_vdb, density, 0.01)
    optics = firncore.VolumeOptics(1.4, (1.0 - 1e-7,) * 3, 0.0)
    stats = firncore.bake(tmp_vdb, optics, sky=firncore.Sky((1.0, 1.0, 1.0)))
    assert stats["traced_voxels"] == stats["light_traced_voxels"] == int((density > 0).sum())
    assert stats["photons"] > 0
    centre = (np.array(density.shape) - 1) / 2 * 0.01
    origins = np.array([centre + [0.0, 0.0, 1.0], centre + [0.1, 0.0, 1.0], centre + [0.0, 0.15, 1.0]])
    radiance = firncore.render_baked(tmp_vdb, optics, origins, np.tile([0.0, 0.0, -1.0], (3, 1)))
    assert np.all(np.abs(radiance - 1.0) < 0.06), radiance  # measured 1.005, 0.977, 0.982


def test_sharp_box_edges_take_and_give_light_face_by_face(folder):
    # The suite's box (12 x 10 x 6 cm, sharp edges, voxels of optical depth 8, omega 0.995, g 0.7) seen across
    # its edges from (120°, 30°) and (220°, 30°), against the core's Monte Carlo (2048 paths per block, noise
    # 2.7 %). With one smooth patch per edge voxel (a diagonal normal: on the edge between the sunlit top and a
    # side facing away, the top's sun never entered) 8.9 % mean, worst +47 %; with the edge voxels taking light
    # in and out through each air face (SurfacePatch::sharp, edgeLobe) 6.8 %, worst +26 % (docs/bake.md).
    result = baked_against_reference(folder, "box_sharp", 2048, [(120, 30), (220, 30)])
    assert result["mean"] < 0.075
    assert result["worst"] < 0.35


def test_thin_forward_ball_holds_light_scattered_a_few_times_in_its_peaked_lobe(folder):
    # A ball under one transport mean free path across (voxels of optical depth 1, all traced; omega 0.999,
    # g 0.85) from the sun's side, across, against the sun and from above. At g 0.85 light scattered a few times
    # is itself peaked: with the peaked lobe holding the beams' single scattering only and the rest in the broad
    # lobe (k <= 1/3) the views were -17 %, +17 %, -10 %, -16 % against the suite's 16384 paths; with the two
    # lobes fitted to the source's first four Legendre moments about the beam (the core's Monte Carlo gathers
    # them in each traced voxel) -3 %, +6 %, -0 %, -2 %.
    result = baked_against_reference(folder, "ball_thin_forward", 2048)
    assert all(abs(b) < 0.10 for b in result["view_bias"]), result["view_bias"]


def test_thin_forward_slab_fitted_by_direction_shows_what_cameras_see(folder):
    # A light dusting: three layers of optical depth 1 (omega 0.9999, g 0.87), all 1728 voxels traced, seen from
    # above, steeply from above across the sun, and along the sun's beam. Its source is not symmetric about the
    # beam (light travelling along the layer stays in it), which no lobe pair fitted to the moments about the beam
    # holds: +8 %, +20 %, -13 % against the suite's 16384 paths (2 seeds). Fitted to the exact source gathered in
    # 39 directions, weighted by the voxel's visibility from each: -3 %, +5 %, -6 % (docs/bake.md, Method 3).
    result = baked_against_reference(folder, "slab_thin_forward", 2048, views=[(0, 60), (90, 75), (180, -30)])
    assert all(abs(b) < 0.12 for b in result["view_bias"]), result["view_bias"]


def test_flat_layer_of_light_traced_snow_pools_its_source_by_direction_over_the_layer(folder):
    # slab_thin_forward (three layers of optical depth 1, omega 0.9999, g 0.87; all 1728 voxels light traced and
    # fitted by direction), seeds 0 and 1 against one reference of the core's Monte Carlo (4096 paths per block:
    # 4.9 % noise per block, about 0.4 % on a view's sum of some 150 blocks). Each voxel's own source towards the
    # fit's directions: mean error per block 11.1, 10.6 %, views +2, +9, +10, +16, -5 % (main c2a28b3). Summed over
    # its flat layer's same-density neighbours and scaled to its own l0 (pooled_estimates.h): 8.7, 8.4 %, views
    # -0, +6, +6, +11, +2 % (docs/bake.md, Method 3). One seed's mean moves by 0.3-0.5 points.
    result = over_seeds_against_reference(folder, "slab_thin_forward", 4096, seeds=2)
    assert result["mean"] < 0.095, result["mean"]
    assert all(abs(b) < 0.13 for b in result["view_bias"]), result["view_bias"]


def test_forward_scattering_traced_voxels_are_light_traced_at_the_gatherings_cost(folder):
    # ball_thin_forward (160 voxels of optical depth 1, omega 0.999, g 0.85, all traced), seeds 0, 1, 2 against one
    # reference of the core's Monte Carlo (2048 paths per block). Gathered per voxel (1024 paths each), a path's
    # next-event estimates weigh the sun by Henyey-Greenstein (2000x across directions at g 0.85): mean error 7.5 %,
    # the baked render's spread across the seeds 4.9 % per block (seeds 3-5, 6-8: 7.8, 7.7 %; 5.1, 5.0 %; main
    # 34901b0). Light traced within three quarters of the gathering's steps (bake_traced_voxels.cpp, kLightTracedShare;
    # about the same processor seconds): 6.9, 6.8, 7.0 %; spreads 3.9, 4.2, 3.9 % (docs/bake.md, Method 3).
    result = over_seeds_against_reference(folder, "ball_thin_forward", 2048, seeds=3)
    assert result["mean"] < 0.073, result["mean"]
    assert result["spread"] < 0.045, result["spread"]


def test_thrown_lumps_are_traced_whole(folder):
    # 24 lumps of 0.5-1.5 cm radius on 1.5 cm voxels (partly filled, up to optical depth 6 per voxel; omega
    # 0.9999, g 0.85). Pieces of snow of at most 343 connected voxels are traced whole, not diffused (a diffusion
    # over a few voxels has no inside): against the suite's 16384 paths 19.7 % mean, +29 % seen across the
    # light before, 11.9 %, per view -1 %, +6 %, +7 %, +5 % after (with the fitted lobes).
    result = baked_against_reference(folder, "spray_lumps", 2048)
    assert result["mean"] < 0.15
    assert all(abs(b) < 0.12 for b in result["view_bias"]), result["view_bias"]


def test_dense_lumps_show_what_cameras_see_of_their_first_optical_depth(folder):
    # The lumps on 1 cm voxels of up to optical depth 20 (omega 0.999, g 0.85), all traced. A camera sees a thick
    # voxel's first optical depth from its side, most of it in the density's ramp before the voxel, not the
    # voxel's extinction-weighted mean: gathered over the mean the view across the light read +16 % and against
    # it -22 % (seed 0, the suite's 16384 paths); gathered where cameras see the voxels (VisiblePoints), +3 % and
    # -6 % (4 seeds; docs/bake.md, Method 3). Oracle: the core's Monte Carlo of the same scene, 512 paths per block.
    result = baked_against_reference(folder, "spray_dense", 512, views=[(90, 0), (180, 0)])
    assert all(abs(b) < 0.11 for b in result["view_bias"]), result["view_bias"]


def test_traced_voxels_estimates_are_stratified_cheap_ones_longer_and_deterministic(tmp_vdb):
    # ball_thin (voxels of optical depth 1, all 160 traced; omega 0.999, g 0.5). Each traced voxel's points and
    # gathering directions come from a randomly shifted R5 Kronecker sequence (monte_carlo.cpp), and paths this
    # cheap are traced 1024 per voxel instead of 256 (bake_traced_voxels.cpp, planGathering: 0.2 processor seconds in
    # all). Two seeds' renders differ by 0.8 % per block on average (|a - b| / (a + b) over the suite's blocks): 1.4 %
    # with the sequence alone, 1.9 % with independent draws at 256 paths (main 37060a5). Same seed, same grids, on
    # 1 or 2 threads. Its accuracy against the core's Monte Carlo: test_small_balls_match_monte_carlo (4.0 % mean
    # over 4 seeds against 4.8 % before; docs/bake.md, Method 3).
    c = case("ball_thin")
    bake_suite.write_density(tmp_vdb, c.density, c.voxel)
    origins, directions, tau = bake_suite.views(c)
    seen = tau >= 1.0

    def render(seed, threads=0):
        firncore.set_thread_count(threads)
        try:
            stats = firncore.bake(tmp_vdb, c.optics, suns=c.suns(), sky=c.skies(), seed=seed)
        finally:
            firncore.set_thread_count(0)
        assert stats["traced_voxels"] == 160
        return firncore.render_baked(tmp_vdb, c.optics, origins, directions)[seen]

    a, b = render(1), render(2)
    assert np.mean(np.abs(a - b) / (a + b)) < 0.012
    assert np.array_equal(render(1, threads=1), a)
    assert np.array_equal(render(1, threads=2), a)


def test_cloud_of_lumps_left_to_the_diffusion_lights_itself_over_many_bounces(tmp_vdb):
    # 216 lumps of 19 voxels (1.2 cm balls on 1 cm voxels, 40 optical depths per voxel, g 0.845: the skier
    # sample's, docs/spray.md) 5 cm apart in a 31 cm cube: too costly to gather per voxel, and light tracing turned
    # off (light_tracing=False), so the diffusion takes them, with a far occluder (as the skier's body). Under a
    # uniform sky they
    # light each other over many bounces; the core's Monte Carlo (all orders) is the oracle. Measured: the bake
    # +0.9 % seen from the side (one gathering bounce, as before: -20 %; two without the rest of the series:
    # -15 %); the reference's noise is under 1 %.
    lump = bake_suite.ball(0.012, 0.01, pad=1) * 250.0
    n, step, size = 6, 5, lump.shape[0]
    side = (n - 1) * step + size
    density = np.zeros((side, side, side))
    for i, j, k in np.ndindex(n, n, n):
        box = tuple(slice(a * step, a * step + size) for a in (i, j, k))
        density[box] = np.maximum(density[box], lump)
    bake_suite.write_density(tmp_vdb, density, 0.01)
    optics = firncore.VolumeOptics(16.0, (0.99998,) * 3, 0.845)
    sky = firncore.Sky((1.0, 1.0, 1.0))
    far = (np.array([[100, 100, -50], [100.1, 100, -50], [100, 100.1, -50]], np.float32), np.array([[0, 1, 2]], np.uint32),
           (0.5, 0.5, 0.5))
    stats = firncore.bake(tmp_vdb, optics, sky=sky, occluders=[far], quality="DRAFT", light_tracing=False)
    assert stats["traced_voxels"] == 0
    u = (np.arange(16) + 0.5) / 16 * side * 0.01
    U, V = np.meshgrid(u, u)
    origins, directions = np.stack([U.ravel(), np.full(U.size, -0.5), V.ravel()], 1), np.tile([0.0, 1.0, 0.0], (U.size, 1))
    reference = firncore.monte_carlo_radiance(tmp_vdb, optics, origins, directions, sky=sky, occluders=[far], samples=64,
                                              seed=1)[0]
    baked = firncore.render_baked(tmp_vdb, optics, origins, directions, occluders=[far])
    assert baked.sum() / reference.sum() == pytest.approx(1.0, abs=0.05)


def test_a_lump_in_the_shadow_of_another_keeps_little_of_the_sun(tmp_path):
    # Two of the skier sample's lumps (1.2 cm, 40 optical depths per voxel at the centre, g 0.845) in line with a
    # sun 26.6 degrees high, B 11 cm behind A (bench/sun_spread_bench.py). Oracle: the core's Monte Carlo, B's
    # light behind A over its light alone (0.10 at 64 paths; 0.47 baked when B's sunlit patches took the sun
    # from up to 3.5 voxels out along their normals, beside A's shadow; 0.03 since, docs/benchmarks.md
    # "sun-spread": what A scatters forwards and sends back is missing).
    import lumps_between_bench
    import sun_spread_bench
    towards = sun_spread_bench.TOWARDS_SUN / np.linalg.norm(sun_spread_bench.TOWARDS_SUN)
    light = dict(suns=[firncore.SunLight(tuple(towards), (1.0,) * 3, 0.0093)], sky=firncore.Sky((0.0,) * 3))
    ground = [lumps_between_bench.plane(-0.05, 0.0)]
    light_on_b = {}
    for steps in (0, 5):
        density, centre, radius = sun_spread_bench.pair_density(steps)
        origins, directions = lumps_between_bench.views_of(centre, radius, 14, 6)
        path = str(tmp_path / f"pair_{steps}.vdb")
        light_on_b[steps] = lumps_between_bench.measure(firncore, path, density, origins, directions, light, ground, 16)
    (baked_alone, mc_alone, _), (baked_behind, mc_behind, mc_error) = light_on_b[0], light_on_b[5]
    assert mc_behind / mc_alone < 0.2, "the Monte Carlo's shadow"  # the oracle itself: A hides B
    assert baked_behind / baked_alone < 2.0 * (mc_behind + 3.0 * mc_error) / mc_alone


def test_lumps_resting_on_the_snows_surface_mesh_are_traced_at_their_own_cost(tmp_vdb):
    # 64 of the skier sample's lumps (1.2 cm balls on 1 cm voxels, 40 optical depths per voxel, g 0.845; 1216 voxels)
    # 5 cm apart, their lowest voxels half inside a closed box standing for the snow under them (its top through those
    # voxels' centres, the snow's white-sky albedo, as spray/light.py meshes the snow one voxel under its surface),
    # under a high sun and a black sky, seen from 50 degrees up. Oracle: the core's Monte Carlo of the lumps over that
    # box (32 paths per pixel, noise of the sum 1.9 %). Paths gathered from points inside the box bounced ~700 times
    # there (albedo 0.998), and the planner left every lump to the diffusion: traced 0, -40 % (25 lumps: all
    # traced, 10.7 processor s, -7 %: the inside's dark points counted). Points inside an occluder gather nothing
    # (monte_carlo.cpp, enclosed): all 1216 traced, +1.4 % (6.8 processor s of tracing).
    lump = bake_suite.ball(0.012, 0.01, pad=1) * 250.0
    n, step, size = 8, 5, lump.shape[0]
    side = (n - 1) * step + size
    density = np.zeros((side, side, size))
    for i, j in np.ndindex(n, n):
        box = (slice(i * step, i * step + size), slice(j * step, j * step + size))
        density[box] = np.maximum(density[box], lump)
    bake_suite.write_density(tmp_vdb, density, 0.01)
    lowest = min(k for k in range(size) if density[:, :, k].max() > 0)  # voxel k spans (k -+ 0.5) cm
    lo, hi = (-0.5, -0.5, -0.3), (side * 0.01 + 0.5, side * 0.01 + 0.5, lowest * 0.01)
    corners = np.array([[(lo, hi)[c & 1][0], (lo, hi)[c >> 1 & 1][1], (lo, hi)[c >> 2][2]] for c in range(8)],
                       np.float32)
    quads = [(0, 2, 3, 1), (4, 5, 7, 6), (0, 1, 5, 4), (2, 6, 7, 3), (0, 4, 6, 2), (1, 3, 7, 5)]  # wound outwards
    triangles = np.array([[q[0], q[k], q[k + 1]] for q in quads for k in (1, 2)], np.uint32)
    snow = [(corners, triangles, (0.972, 0.987, 0.998))]
    optics = firncore.VolumeOptics(16.36, (0.99998,) * 3, 0.845)
    light = dict(suns=[firncore.SunLight((0.3, -0.2, 0.93), (1.0,) * 3, 0.0093)], sky=firncore.Sky((0.0,) * 3))
    stats = firncore.bake(tmp_vdb, optics, occluders=snow, quality="FINAL", **light)
    assert stats["traced_voxels"] == int((density > 0).sum())
    e = math.radians(50.0)
    back = np.array([0.0, -math.cos(e), math.sin(e)])
    u = (np.arange(24) + 0.5) / 24 * side * 0.01
    X, Y = np.meshgrid(u, u)
    origins = np.stack([X.ravel(), Y.ravel(), np.full(X.size, 0.01)], 1) + 0.5 * back
    directions = np.tile(-back, (X.size, 1))
    reference = firncore.monte_carlo_radiance(tmp_vdb, optics, origins, directions, occluders=snow, samples=32,
                                              seed=1, **light)[0]
    baked = firncore.render_baked(tmp_vdb, optics, origins, directions, occluders=snow)
    assert baked.sum() / reference.sum() == pytest.approx(1.0, abs=0.1)


def test_lumps_over_the_snows_surface_mesh_too_many_to_gather_are_light_traced(tmp_path):
    # bench/spray_light_bench.py's ski spray (the last of 12 frames: 793 lump voxels of 2 cm, up to 20 optical depths,
    # g 0.89) over the snow's surface mesh (closed, one voxel under the surface, the snow's white-sky albedo), as Bake
    # Sequence bakes the lumps: over the gathering budget. Until branch spray-trace any occluder left such voxels to
    # the diffusion: +32 % against the core's Monte Carlo of the same scene (64 paths per pixel, 32 x 16 pixels), the
    # bench's 256-path reference 34 % per block, bias +26 %. Light traced: +4.9 % (the bench over bake seeds 0-3
    # -0.2 to +1.6 % bias, 8.3-9.8 % per block; docs/bake.md Method 3). light_tracing=False keeps the diffusion.
    import spray_light_bench as spray_bench
    tracked, spray = spray_bench.ski_spray(str(tmp_path), firncore.SpraySettings(seed=5))
    voxel = firncore.grid_statistics(tracked, "surface")["voxel_size"]
    surface = firncore.snow_surface_mesh(tracked, adaptivity=0.5, isovalue=-voxel)
    snow = [(*surface, spray_bench.OPTICS.white_sky_albedo)]
    light = dict(suns=spray_bench.SUNS, sky=spray_bench.SKY, occluders=snow)
    lit = str(tmp_path / "lit_spray.vdb")
    diffused = firncore.bake(spray, spray_bench.OPTICS, output_path=lit, light_tracing=False, **light)
    assert diffused["traced_voxels"] == diffused["light_traced_voxels"] == 0
    stats = firncore.bake(spray, spray_bench.OPTICS, output_path=lit, **light)
    lumps = firncore.grid_statistics(spray, "density")["active_voxels"]
    assert stats["light_traced_voxels"] == stats["traced_voxels"] == lumps
    origins, directions, _shape = spray_bench.view("side", 32)
    reference = firncore.monte_carlo_radiance(spray, spray_bench.OPTICS, origins, directions, samples=64, seed=1,
                                              **light)[0]
    baked = firncore.render_baked(lit, spray_bench.OPTICS, origins, directions)
    assert baked.sum() / reference.sum() == pytest.approx(1.0, abs=0.12)
    # DRAFT, a preview, traces a quarter of the photons (bake.cpp, Preset::lightTracingShare; until branch
    # trace-quality as many as FINAL: the bench's lumps 9.9 processor s at either quality, now 2.7, 8.9 -> 10.6 % per
    # block off) and stays within the same bound: 394,009 photons against 1,632,609, +4.0 % (FINAL +4.9 %).
    draft = firncore.bake(spray, spray_bench.OPTICS, output_path=lit, quality="DRAFT", **light)
    assert draft["light_traced_voxels"] == lumps
    assert 0 < draft["photons"] < stats["photons"] / 2
    baked = firncore.render_baked(lit, spray_bench.OPTICS, origins, directions)
    assert baked.sum() / reference.sum() == pytest.approx(1.0, abs=0.12)
    # The joint bake of the tracked snow with the lumps in it (Bake Sequence's other bake) light traces 628 of the
    # lumps' voxels (docs/spray.md "Light", 17.8 processor s); light_tracing=False keeps its diffusion (0.7 s).
    joint = firncore.bake_joint([tracked, spray], [None, None], spray_bench.OPTICS,
                                suns=spray_bench.SUNS, sky=spray_bench.SKY, light_tracing=False)
    assert joint["light_traced_voxels"] == joint["photons"] == 0
    # At DRAFT it light traces them with a quarter of FINAL's photons, under the least FINAL accepts (65,536): that
    # least scales with the share, else the diffusion took them and the snow with the lumps seen from above read
    # 29.8 % per block off instead of 13.1 % (FINAL 10.2 %; docs/spray.md "Light").
    joint = firncore.bake_joint([tracked, spray], [None, None], spray_bench.OPTICS,
                                suns=spray_bench.SUNS, sky=spray_bench.SKY, quality="DRAFT")
    assert 0 < joint["photons"] < 65536 and joint["light_traced_voxels"] > 0
    # What it baked, seen from above (the bench's "above" view at 32 x 16 pixels): bake_joint bakes the union of its
    # densities (bind_transport.cpp: unionDensity, then bakeScattering) and writes each object's part, which
    # render_baked cannot draw together; union_density writes that union, whose bake is the same bake (the same plan
    # and photons), drawn whole, against the core's Monte Carlo of that union. Oracle: 16 paths per pixel, noise some
    # 12 % per 4 x 4 block, 3 % on the sum. Measured: bake seeds 0-2 17.1, 17.8, 14.5 % per block, bias +2.1, +2.3,
    # +3.2 %; the diffusion (light_tracing=False, where the least photons stayed 65,536) 41.3 %, +13.6 %.
    from block_compare import blocks
    union = str(tmp_path / "union.vdb")
    firncore.union_density([tracked, spray], union)
    lit_union = str(tmp_path / "lit_union.vdb")
    baked_union = firncore.bake(union, spray_bench.OPTICS, output_path=lit_union, quality="DRAFT",
                                suns=spray_bench.SUNS, sky=spray_bench.SKY)
    assert baked_union["photons"] == joint["photons"]
    origins, directions, shape = spray_bench.view("above", 32)
    reference = firncore.monte_carlo_radiance(union, spray_bench.OPTICS, origins, directions, samples=16, seed=1,
                                              suns=spray_bench.SUNS, sky=spray_bench.SKY)[0]
    baked = blocks(firncore.render_baked(lit_union, spray_bench.OPTICS, origins, directions).mean(1), shape)
    reference = blocks(reference.mean(1), shape)
    lit = reference > 0.05 * reference.max()  # block_compare.compare's blocks with light
    assert np.abs(baked[lit] / reference[lit] - 1).mean() < 0.28
    assert baked[lit].sum() / reference[lit].sum() == pytest.approx(1.0, abs=0.08)


def test_a_lone_lumps_sharp_edges_return_the_grazing_sun_forwards(tmp_path):
    # The skier sample's lump (1.2 cm, 19 voxels: 12 of them sharp edges, two air faces at right angles) left to the
    # diffusion by 400 far lumps, under a sun 17.6 degrees high, seen nearly level 27 degrees off the sun's travel
    # (bench/lump_angles_bench.py's B alone, view -0.89). Oracle: the core's Monte Carlo (256 paths per pixel, noise
    # 1.6 %). Its rim against the sun is the sun entering the edges' faces at grazing incidence and scattered on
    # forwards, which a half-space returns sharply forwards (SunPeak). Measured: -42.7 % when the edge faces returned
    # it in the sun lobe's linear shape, -20.5 % with each face's peak in the voxel's peaked lobe (docs/benchmarks.md
    # "lump-lobe").
    import cluster_glow_bench
    import lumps_between_bench
    light = cluster_glow_bench.sun_off_the_neighbours(firncore)
    density, centre, radius = lumps_between_bench.cluster_density(1, False)
    origins, directions = lumps_between_bench.views_of(centre, radius, 14, 16)
    per = len(origins) // 14
    view = slice(6 * per, 7 * per)  # the Fibonacci sphere's view 6: cosine -0.89 with the sun's direction
    assert -directions[view][0] @ np.array(cluster_glow_bench.SUN_TOWARDS) == pytest.approx(-0.89, abs=0.01)
    baked, mc, mc_error = lumps_between_bench.measure(firncore, str(tmp_path / "lump.vdb"), density, origins[view],
                                                      directions[view], light, [lumps_between_bench.plane(-0.03, 0.0)],
                                                      256)
    assert mc_error / mc < 0.05
    assert 0.69 < baked / mc < 1.25  # midway between the linear shape's 0.573 and the peak's 0.795, 6 sigma each


def test_a_walls_lowest_voxel_on_the_ground_takes_the_sun_as_the_wall_above(tmp_vdb):
    # A box of bumpy_plate's snow (tau 15 per voxel, omega 0.999, g 0.7) standing on a grey ground, the sun 30
    # degrees high facing its wall; seen 10 degrees from above at the wall's lowest voxel and the two above it.
    # Oracle: the core's Monte Carlo (512 paths per ray, noise 1.2 %). Measured: lowest voxel -19.9 %, above -2.9 %
    # when the voxel's normal read the empty row under the ground as air (tilted 45 degrees towards the ground);
    # +4.3 %, +1.8 % since the normal reads its own layer across an occluder (docs/bake.md Method 1); +10.5 %, +5.2 %
    # since the ground sends the wall's own light back (Method 6): the lowest voxel reads +13.6 % over a black ground
    # (no ground light at all), a surplus the missing ground light had hidden (docs/benchmarks.md "ground-bounce").
    import wall_on_ground_bench as wall
    light = dict(suns=[firncore.SunLight((math.cos(math.pi / 6), 0.0, 0.5), (1.0,) * 3, 0.0093)],
                 sky=firncore.Sky((0.05,) * 3))
    _, _, optics, ground = wall.baked_box(tmp_vdb, 0.5, light)
    # voxels: the lowest (its centre at 2), then the next two; the bounds keep the tilted normal's -19.9 % out. The
    # lowest voxel's upper bound is wider, not its lower: its surplus is known (+13.6 % over a black ground, light the
    # ground cannot take away), a shortfall would be the ground's light lost again.
    for heights, (low, high) in (((2.25, 2.75), (-0.08, 0.13)), ((3.5, 4.5), (-0.08, 0.08))):
        origins, directions = wall.wall_rays(heights, 10.0, 0.2)
        reference, error = firncore.monte_carlo_radiance(tmp_vdb, optics, origins, directions, occluders=ground,
                                                         samples=512, seed=5, **light)
        baked = firncore.render_baked(tmp_vdb, optics, origins, directions, occluders=ground)
        assert np.sqrt((error[:, 1] ** 2).sum()) < 0.03 * reference[:, 1].sum()
        assert low < baked[:, 1].sum() / reference[:, 1].sum() - 1.0 < high


def test_a_wall_lit_from_above_only_sends_its_sky_on_downwards(tmp_vdb):
    # The same box on a black ground under the sky alone: the wall's sky arrives from above only, and g 0.7 carries
    # it on downwards, so the wall is brighter seen from below than from above (the Monte Carlo: 0.0218 seen from
    # 55 degrees above, 0.0251 from 30 degrees below, rows 4-6). Oracle: the core's Monte Carlo, 512 paths per
    # ray (noise about 1.5 % per view). Measured: baked / reference +10.7 % from above and -5.5 % from below when
    # the returned sky left evenly (a lean of 17 %); +0.9 %, +0.2 % since it leans as its beam part would
    # (skyBeamPart, docs/bake.md Method 5).
    import wall_on_ground_bench as wall
    sky = firncore.Sky((0.05,) * 3)
    _, _, optics, ground = wall.baked_box(tmp_vdb, 0.0, dict(sky=sky))
    ratios = []
    for elevation in (55.0, -30.0):  # of the view above the horizon
        origins, directions = wall.wall_rays((4.0, 5.0, 6.0), elevation, 0.03)
        reference, error = firncore.monte_carlo_radiance(tmp_vdb, optics, origins, directions, occluders=ground,
                                                         samples=512, seed=5, sky=sky)
        baked = firncore.render_baked(tmp_vdb, optics, origins, directions, occluders=ground)
        assert np.sqrt((error[:, 1] ** 2).sum()) < 0.03 * reference[:, 1].sum()
        ratios.append(baked[:, 1].sum() / reference[:, 1].sum())
    assert ratios[0] == pytest.approx(1.0, abs=0.06)
    assert ratios[0] / ratios[1] == pytest.approx(1.0, abs=0.08)


def test_a_pile_of_lumps_on_a_white_ground_takes_back_the_light_it_sends_the_ground(tmp_path):
    # 27 of the skier sample's lumps (1.2 cm, 19 voxels, 40 optical depths per voxel, g 0.845) 5 cm apart, the lowest
    # row resting on a ground of albedo 0.97, left to the diffusion by 400 far lumps, under a sun 30 degrees high
    # (bench/lumps_between_bench.py's pile). What the white ground adds to the middle lump B against a black one:
    # its reflection of the sun and of the snow's own light, which the pile's lumps send down and take back over
    # many bounces. Oracle: the core's Monte Carlo (all orders; 128 paths per pixel, noise of the gain about 2 %).
    # Measured: baked / Monte Carlo 0.63 when the occluders reflected sun and sky only, 0.81 since the gathering
    # takes what they reflect of the snow's light (docs/benchmarks.md "ground-bounce").
    import lumps_between_bench
    e = math.radians(30.0)
    light = dict(suns=[firncore.SunLight((math.cos(e), 0.0, math.sin(e)), (1.0,) * 3, 0.0093)],
                 sky=firncore.Sky((0.0,) * 3))
    density, centre, radius = lumps_between_bench.cluster_density(0, True)
    origins, directions = lumps_between_bench.views_of(centre, radius, 14, 6)
    on_b = {albedo: lumps_between_bench.measure(firncore, str(tmp_path / "pile.vdb"), density, origins, directions,
                                                light, [lumps_between_bench.plane(0.06, albedo)], 128)
            for albedo in (0.0, 0.97)}
    (baked_black, mc_black, error_black), (baked_white, mc_white, error_white) = on_b[0.0], on_b[0.97]
    mc_gain, baked_gain = mc_white - mc_black, baked_white - baked_black
    assert math.hypot(error_black, error_white) < 0.05 * mc_gain
    assert 0.72 < baked_gain / mc_gain < 1.25  # midway between 0.63 and 0.81 at the low end; no double count


def baked_source_toward(path, voxels, w):
    """The baked source function (W/m^2/sr) at voxel centres `voxels` (index space) towards unit w, green channel, as
    the contract reads the six grids (docs/vdb-contract.md): the broad lobe l0, l1 and the peaked lobe p0 with its
    grey moment p1, each Henyey-Greenstein of k = |moment| / (3 mean), at most firncore.LOBE_MAX_ANISOTROPY."""
    import pyopenvdb
    grids = {g.name: g.getConstAccessor() for g in pyopenvdb.readAll(path)[0]}

    def lobe(mean, moment):
        length = np.linalg.norm(moment)
        if mean <= 0.0 or length <= 0.0:
            return max(mean, 0.0)
        k = min(length / (3.0 * mean), firncore.LOBE_MAX_ANISOTROPY)
        cosine = np.dot(w, moment) / length
        return mean * (1.0 - k * k) / (1.0 + k * k - 2.0 * k * cosine) ** 1.5

    out = []
    for v in voxels:
        c = tuple(int(x) for x in v)
        l0 = grids["firn_source"].getValue(c)[1]
        l1 = np.array([grids["firn_source_" + a].getValue(c)[1] for a in "xyz"])
        p0 = np.array(grids["firn_source_peak"].getValue(c))
        p1 = np.array(grids["firn_source_peak_l1"].getValue(c))
        out.append(lobe(l0, l1) + (p0[1] / p0.mean() * lobe(p0.mean(), p1) if p0.mean() > 0.0 else 0.0))
    return np.array(out)


def test_ramp_past_the_terminator_scatters_at_least_the_suns_single_scattering(folder):
    # Every order of scattering adds light, so the source function is at least the sun's single scattering,
    # omega E T HG(g, cos) (HG normalized over 4 pi sr), and a voxel's value, weighed by the renderer's emission over
    # its trilinear hat, at least that with T averaged over the hat weighted by the density. The grey ball (omega 0.9,
    # g 0.6, voxels of optical depth 5): the voxels of its density ramp and just outside it (centre under half the
    # density, the hat holding at least 1 % of a full voxel's snow: what emits), around the limb where the surface
    # takes the sun at grazing incidence or not at all (the radial normal's mu0 from -0.3 to 0.2), reach into the sun
    # (T averaged so 0.2 to 0.63: 52 voxels), while the surface voxels whose radiance they carry have no sun in their
    # half-space model. Towards the sun's travel (where single scattering peaks) main's carried radiance held 0.33 to
    # 2.0 of that bound (36 of the 52 below 0.9); with the ramp's own single scattering where it holds more
    # (bake_grid_values.cpp, beamsInRamp: the core's T over 4^3 points, this test's over 6^3) 1.13 to 2.0 (docs/bake.md,
    # Method 7; ball_grey 10.1 -> 9.5 % per block, seen against the sun -12.1 -> -11.1 %). Voxels whose hat holds
    # less (0.3 % of a voxel's snow, r 6.7 voxels) take their neighbours' average and read 0.73 of it.
    c = case("ball_grey")
    path = os.path.join(folder, "ramp_sun.vdb")
    bake_suite.write_density(path, c.density, c.voxel)
    firncore.bake(path, c.optics, suns=c.suns(), sky=c.skies(), seed=0, source_scale=1)
    sun = np.array([math.cos(bake_suite.SUN_ELEVATION), 0.0, math.sin(bake_suite.SUN_ELEVATION)])
    centre = (np.array(c.density.shape) - 1) / 2
    voxels = np.argwhere(c.density < 0.5 * c.rho)
    radial = (voxels - centre) / np.linalg.norm(voxels - centre, axis=1)[:, None]
    voxels = voxels[(radial @ sun > -0.3) & (radial @ sun < 0.2)]
    # T over the hat: 6^3 points, each marched to the sun on tenth-voxel steps through the trilinear density.
    nodes = (np.arange(6) + 0.5) / 6 * 2.0 - 1.0
    offsets = np.array(np.meshgrid(nodes, nodes, nodes, indexing="ij")).reshape(3, -1).T
    hat = np.prod(1.0 - np.abs(offsets), axis=1)
    steps = np.arange(0.05, 2.0 * max(c.density.shape), 0.1)
    kappa = c.sigma_t / c.rho * c.voxel  # optical depth per (kg/m^3 * voxel)
    ramp, transmittance = [], []
    for v in voxels:
        weights = hat * bake_suite.trilinear(c.density, v + offsets)
        if weights.sum() < 0.01 * c.rho * hat.sum():
            continue  # hardly any snow in its hat: hardly any emission
        tau = [kappa * 0.1 * bake_suite.trilinear(c.density, p + steps[:, None] * sun).sum() for p in v + offsets]
        ramp.append(v)
        transmittance.append(np.sum(weights * np.exp(-np.array(tau))) / weights.sum())
    ramp, transmittance = np.array(ramp), np.array(transmittance)
    lit = transmittance >= 0.2
    assert lit.sum() >= 40, lit.sum()
    g = c.g
    single = c.omega[1] * c.sun * transmittance[lit] * (1.0 + g) / (4.0 * math.pi * (1.0 - g) ** 2)
    baked = baked_source_toward(path, ramp[lit], -sun)
    assert np.all(baked > 0.9 * single), np.round(baked / single, 2)


def test_ramp_single_scattering_keeps_a_second_suns_forward_peak(folder):
    # Light adds: the grey ball under the suite's 30-degree sun and a second, overhead sun keeps the overhead sun's
    # forward peak. The voxels beside the snow near the low sun's terminator (the radial normal's mu0 from -0.3 to 0.2
    # for it: beamsInRamp's gate passes it) on the overhead sun's lit side (mu0 >= 0.3: the gate fails it, the surface
    # model holds its light) carry a peaked lobe; the part of its grey first moment perpendicular to the low sun's
    # travel is what the low sun's single scattering lacks. Where the overhead sun alone gives that part (>= 0.005
    # W/m^2/sr, 22 of 80 voxels), the two suns' bake once held 0.41 of it in sum (beamsInRamp replaced the voxel's whole
    # peak by the low sun's single scattering where that summed more, some to 0); kept whole where a sun the
    # surface takes lights the voxel, 0.83 (the low sun's carried peak leans the other way in some: the bake's carried
    # peaks through the ramp, forwardPeakThrough, are not a sum over suns). The bound lies midway.
    import pyopenvdb
    c = case("ball_grey")
    low = np.array([math.cos(bake_suite.SUN_ELEVATION), 0.0, math.sin(bake_suite.SUN_ELEVATION)])
    high = np.array([0.0, 0.0, 1.0])
    across = -high + np.dot(high, low) * low  # the overhead sun's travel less its part along the low sun's
    across /= np.linalg.norm(across)
    snow = np.pad(c.density > 0.0, 1)
    beside = np.zeros_like(snow)  # within one voxel of snow
    for shift in np.ndindex(3, 3, 3):
        beside[1:-1, 1:-1, 1:-1] |= snow[tuple(slice(s, s + n) for s, n in zip(shift, c.density.shape))]
    voxels = np.argwhere(beside[1:-1, 1:-1, 1:-1] & (c.density < 0.5 * c.rho))
    radial = voxels - (np.array(c.density.shape) - 1) / 2
    radial /= np.linalg.norm(radial, axis=1)[:, None]
    voxels = voxels[(radial @ low > -0.3) & (radial @ low < 0.2) & (radial @ high >= 0.3)]
    overhead = firncore.SunLight(tuple(high), (c.sun,) * 3, 0.0093)
    moment = {}  # per voxel the peaked lobe's grey first moment (3 k m mean p0) across
    for name, suns in (("both", c.suns() + [overhead]), ("high", [overhead])):
        path = os.path.join(folder, "two_suns_" + name + ".vdb")
        bake_suite.write_density(path, c.density, c.voxel)
        firncore.bake(path, c.optics, suns=suns, sky=c.skies(), seed=0, source_scale=1)
        peak1 = next(g for g in pyopenvdb.readAll(path)[0] if g.name == "firn_source_peak_l1").getConstAccessor()
        moment[name] = np.array([np.dot(peak1.getValue(tuple(int(x) for x in v)), across) for v in voxels])
    lit = moment["high"] >= 0.005
    assert lit.sum() >= 15, lit.sum()
    kept = moment["both"][lit].sum() / moment["high"][lit].sum()
    assert kept > 0.62, kept


def test_peaks_carried_past_the_terminator_take_the_sun_where_the_ramp_voxel_holds_snow(folder):
    # ball_grey (omega 0.9, g 0.6) seen against the sun: the equator's side rims past the terminator (view (180, 0)
    # blocks 24, 31, 32, 39) cross ramp voxels whose carriers face away from the sun (mu0 -0.5 to -0.2). The lit
    # surfaces' forward peaks carried there (forwardPeakThrough) are weighed by the share of the sun reaching the
    # voxel; taken at its centre an air voxel beside the limb reads T = 1 while the snow in its hat, which is what the
    # renderer weighs its value by, lies in the body's shadow. The sun alone against these 4096 Monte Carlo paths:
    # +269 % with T at the centre, +144 % with T averaged over the hat (branch
    # grey-rims; docs/benchmarks.md); the bound lies midway. What is left is the carried peak's own size.
    bias = sun_alone_against_monte_carlo(folder, "ball_grey", [24, 31, 32, 39])
    assert bias < 2.0, bias


def test_ramp_of_a_small_thick_ball_scatters_the_sun_crossing_its_rim(folder):
    # Seen against the sun, a small thick ball's top rim and side rims (ball_issue's and ball_grey's outermost blocks
    # of view (180, 0): 58-61, 40, 47) show the sun that entered the density ramp's outer part on a long chord and
    # scattered a few times there (the core's Monte Carlo: 75 % of ball_issue's entered outside r + 0.3 voxels,
    # orders 2-8 most; docs/benchmarks.md, rim-forward), not the surface's half-space return the ramp carries. With
    # the ramp's own sun scattering added to the carried peaks where the ramp lies beside thick convex snow
    # (beamsInRamp) the sun alone reads, against these 4096 paths (the sum's noise 1.4 %, 0.5 %): ball_issue
    # -31.1 % -> -25.1 %, ball_grey -31.6 % -> -24.8 %; the lower bound lies midway. The upper bound catches a double
    # count: the ramp's added sun is single scattering (p(30 deg) 0.176 at g 0.85) where the orders 2-8 that bring
    # most of this light reach the camera through a broader lobe (p 0.27), so the bake stays below the Monte Carlo;
    # counting ball_issue's carried peaks twice (0.96 of its blocks' 1.38 baked on main) would read about +30 %.
    # -0.10 lies 15 points above the measured figures (10 times ball_issue's sum noise) and that far below 0.
    for name in ("ball_issue", "ball_grey"):
        bias = sun_alone_against_monte_carlo(folder, name, [58, 59, 60, 61, 40, 47])
        assert -0.28 < bias < -0.10, (name, bias)


@functools.cache
def thin_slab_baked(folder):
    """slab_thin_forward (sigma_t h 1: every voxel thin) baked, with its camera rays (seen ones); once for the module,
    so a test that changes the file changes a copy."""
    c = case("slab_thin_forward")
    path = os.path.join(folder, "thin_slab_scattered.vdb")
    bake_suite.write_density(path, c.density, c.voxel)
    firncore.bake(path, c.optics, suns=c.suns(), sky=c.skies(), quality="FINAL", seed=0)
    origins, directions, tau = bake_suite.views(c)
    seen = np.nonzero(tau >= 1.0)[0][::12]
    return c, path, origins[seen], directions[seen]


def test_render_scattering_nowhere_is_the_baked_render(folder):
    # Under a threshold no voxel passes, the render is the baked emission alone, as render_baked draws it.
    c, path, origins, directions = thin_slab_baked(folder)
    mixed, _ = firncore.render_scattering_where_thin(path, c.optics, origins, directions, suns=c.suns(), sky=c.skies(),
                                                     samples=4, thin_depth=0.0)
    assert mixed == pytest.approx(firncore.render_baked(path, c.optics, origins, directions), rel=1e-9)


def test_render_scattering_where_all_snow_is_thin_is_the_monte_carlo(folder):
    # Every voxel thin (and the air beside it): the render scatters everywhere and draws no baked emission, so it
    # is the brute-force path tracing of the same scene; its estimate and the reference's agree within their noise.
    c, path, origins, directions = thin_slab_baked(folder)
    mixed, mixed_error = firncore.render_scattering_where_thin(path, c.optics, origins, directions, suns=c.suns(),
                                                               sky=c.skies(), samples=16384, seed=5, thin_depth=2.0)
    truth, truth_error = firncore.monte_carlo_radiance(path, c.optics, origins, directions, suns=c.suns(),
                                                       sky=c.skies(), samples=16384, seed=7)
    difference = mixed[:, 1].sum() - truth[:, 1].sum()
    sigma = math.sqrt((mixed_error[:, 1] ** 2).sum() + (truth_error[:, 1] ** 2).sum())
    assert sigma < 0.012 * truth[:, 1].sum()  # low enough to tell the baked render (+5 % here) apart
    assert abs(difference) < 4.0 * sigma


def test_scatter_voxels_are_the_thin_snow(folder):
    # slab_thin_forward's voxels are all sigma_t h 1, all traced: the renderer scatters the slab's whole density (the
    # firn_scatter grid proposed in benchmarks.md, thin-ring), no air voxel listed; under 1 in none.
    c = case("slab_thin_forward")
    path = os.path.join(folder, "thin_slab_scatter_voxels.vdb")
    bake_suite.write_density(path, c.density, c.voxel)
    on = np.zeros(c.density.shape, dtype=bool)
    voxels = firncore.scatter_voxels(path, c.optics, thin_depth=2.0, traced_only=True)
    on[tuple(voxels.T)] = True
    assert np.array_equal(on, c.density > 0)
    assert len(firncore.scatter_voxels(path, c.optics, thin_depth=1.0, traced_only=True)) == 0


def test_a_flat_top_under_a_partly_filled_voxel_is_not_scattered_twice(folder):
    # ball_issue's snow (omega 0.98, g 0.85, sigma_t h 10: optically thick per voxel, transport-thin) as a flat top
    # under a layer a twentieth full, the sun 30 deg up, seen from above. The layer is thin snow the renderer scatters;
    # the surface voxel under it carries the surface's light (the layer peeled onto it). A share read trilinearly
    # scattered half the surface voxel's density too, and the mixed render read 1.36 times the Monte Carlo; scattering
    # only the layer's own density it reads 1.10 (the baked form 1.05; docs/benchmarks.md lead-94, lead-95).
    c = case("ball_issue")
    density = np.zeros((20, 20, 12), dtype=np.float32)
    rho = c.density.max()  # kg/m^3
    density[2:-2, 2:-2, 2:8] = rho
    density[2:-2, 2:-2, 8] = 0.05 * rho
    path = os.path.join(folder, "flat_top_layer.vdb")
    bake_suite.write_density(path, density, c.voxel)
    spots = (np.arange(4) + 0.5) * 2.0 + 6.0  # voxels: a 4 x 4 bundle over the middle 8 x 8
    origins = np.array([(x, y, 11.0) for x in spots for y in spots]) * c.voxel
    directions = np.tile([0.0, 0.0, -1.0], (len(origins), 1))
    suns = c.suns()  # the sun alone, 30 deg up
    truth, truth_error = firncore.monte_carlo_radiance(path, c.optics, origins, directions, suns=suns, samples=2048,
                                                       seed=11)
    firncore.bake(path, c.optics, suns=suns, quality="FINAL", seed=0)
    assert len(firncore.scatter_voxels(path, c.optics)) == 16 * 16  # the layer, and nothing under it
    mixed, mixed_error = firncore.render_scattering_where_thin(path, c.optics, origins, directions, suns=suns,
                                                               samples=512, seed=3, traced_only=True)
    m, t = mixed[:, 1].sum(), truth[:, 1].sum()
    sigma = math.sqrt((mixed_error[:, 1] ** 2).sum() / m ** 2 + (truth_error[:, 1] ** 2).sum() / t ** 2)
    assert sigma < 0.04  # 0.026
    assert m / t < 1.25


def scatter_grid(path):
    """The firn_scatter grid of a baked file (pyopenvdb), or None where the bake wrote none."""
    import pyopenvdb

    names = firncore.grid_names(path)
    assert names.count(firncore.SCATTER_GRID_NAME) <= 1
    return pyopenvdb.read(path, firncore.SCATTER_GRID_NAME) if firncore.SCATTER_GRID_NAME in names else None


def scatter_on(grid):
    """The voxels of a scattered density > 0 and the set of the grid's active values."""
    values = [(tuple(v.min), v.value) for v in grid.citerOnValues()]
    assert all(v.count == 1 for v in grid.citerOnValues())  # voxels, no tiles (Cycles renders tiles as empty)
    return sorted(ijk for ijk, value in values if value > 0.0), {value for _, value in values}


def coarse_voxels(voxels, scale):
    """The voxels of a grid `scale` times coarser (voxel J where fine voxel scale J is) within `scale` fine voxels of
    one of `voxels` (|v - scale J| <= scale along every axis)."""
    out = set()
    for v in voxels:
        out.update(itertools.product(*[range(-(-x // scale) - 1, x // scale + 2) for x in v]))
    return sorted(out)


def test_a_bake_writes_the_scatter_grid_where_the_renderer_scatters(folder):
    # slab_thin_forward's voxels are all traced and of sigma_t h 1: the bake's own firn_scatter holds the slab's
    # density (the density the renderer scatters) on the coarse voxels (SCATTER_SCALE times the density's) within
    # SCATTER_SCALE density voxels of one scatter_voxels finds (thin-ring's rule B, from the scene alone: every snow
    # voxel here), 0 nowhere; read as Cycles reads it (trilinear, through its own transform) it is the density at
    # each such voxel's centre, 0 four density voxels away from all of them.
    c, path, _, _ = thin_slab_baked(folder)
    grid = scatter_grid(path)
    assert grid is not None
    on, values = scatter_on(grid)
    scale = firncore.SCATTER_SCALE
    assert scale == 2
    fine = sorted(map(tuple, firncore.scatter_voxels(path, c.optics, thin_depth=2.0, traced_only=True)))
    rho = np.float32(c.density.max())  # kg/m^3, the same in every snow voxel
    assert len(fine) == (c.density > 0).sum() and set(c.density[c.density > 0]) == {rho}
    assert on == coarse_voxels(fine, scale) and values == {rho}
    assert grid["firn_scatter_optical_depth"] == 2.0 and grid["firn_units"].startswith("kg/m^3 ")
    import pyopenvdb

    density = pyopenvdb.read(path, "density")
    h, h_s = density.transform.voxelSize()[0], grid.transform.voxelSize()[0]
    assert h_s == pytest.approx(scale * h)
    def centre(transform, ijk, voxel):  # a voxel's centre: the file's grids are shifted by -voxel/2
        return np.array(transform.indexToWorld(tuple(float(i) for i in ijk))) + voxel / 2
    for J in [(3, 5, 7), (-2, 0, 4)]:
        fine_centre = centre(density.transform, tuple(scale * j for j in J), h)
        assert centre(grid.transform, J, h_s) == pytest.approx(fine_centre)
    points = np.array([centre(density.transform, v, h) for v in fine])
    assert firncore.sample_grid(path, firncore.SCATTER_GRID_NAME, points) == pytest.approx(rho, rel=1e-6)
    low = np.min(fine, axis=0) - 5
    near = np.zeros(np.ptp(fine, axis=0) + 11, dtype=bool)
    near[tuple((np.array(fine) - low).T)] = True
    for axis in range(3):  # grown by 3 voxels along each axis in turn: within 3 of a scattering voxel on every axis
        near = np.logical_or.reduce([np.roll(near, d, axis) for d in range(-3, 4)])
    far = np.argwhere(~near) + low
    points = np.array([centre(density.transform, tuple(v), h) for v in far])
    # (the world points' rounding leaves weights of order 1e-8 on the neighbours of a coarse voxel's edge)
    assert len(far) > 0 and np.abs(firncore.sample_grid(path, firncore.SCATTER_GRID_NAME, points)).max() < 1e-6 * rho


def test_the_scatter_grid_goes_with_its_bake(folder):
    # A bake of snow nowhere thin (slab_thick, sigma_t h 30) writes none; baked again over a file holding an
    # earlier bake's scatter grid, the new bake removes it (thin snow again: replaces it, one grid, the same
    # voxels); Clear Bake's remove_grids leaves the snow's grids alone.
    c, baked, _, _ = thin_slab_baked(folder)
    path = os.path.join(folder, "thin_slab_rebaked.vdb")
    shutil.copyfile(baked, path)
    before = scatter_on(scatter_grid(path))
    firncore.bake(path, c.optics, suns=c.suns(), sky=c.skies(), quality="FINAL", seed=1)
    assert scatter_on(scatter_grid(path)) == before

    thick = case("slab_thick")
    thick_path = os.path.join(folder, "thick_slab_scatter.vdb")
    bake_suite.write_density(thick_path, thick.density, thick.voxel)
    import pyopenvdb

    pyopenvdb.write(thick_path, [pyopenvdb.read(thick_path, "density"), scatter_grid(path)])  # an earlier bake's
    stats = firncore.bake(thick_path, thick.optics, suns=thick.suns(), sky=thick.skies(), quality="DRAFT")
    assert stats["scatter_voxels"] == 0 and scatter_grid(thick_path) is None

    removed = firncore.remove_grids(path, [*firncore.BAKED_GRID_NAMES, firncore.SCATTER_GRID_NAME])
    assert sorted(removed) == sorted([*firncore.BAKED_GRID_NAMES, firncore.SCATTER_GRID_NAME])
    assert firncore.grid_names(path) == ["density"]


def test_a_joint_bake_gives_each_output_its_scatter_grid(folder):
    # bake_joint of one file is its bake: the output holds the same scatter grid as `bake` writes.
    c, path, _, _ = thin_slab_baked(folder)
    alone = scatter_on(scatter_grid(path))
    output = os.path.join(folder, "thin_slab_joint.vdb")
    firncore.bake_joint([path], [output], c.optics, suns=c.suns(), sky=c.skies(), quality="FINAL", seed=0)
    assert scatter_on(scatter_grid(output)) == alone
