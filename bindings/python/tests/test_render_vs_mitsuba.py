"""`brdftab render` against Mitsuba 3 on the same scene (bench/render_vs_mitsuba.py builds it):
a Lambertian sphere under a point light and under brdftab's default sky, direct lighting, in
scalar_rgb. Agreement is judged by the noise each renderer measures on itself (two seeds), not
by figures either printed: a π in the radiometry, a light's units or an environment turned
round move the sphere's mean by far more than 5 standard errors (the π: a ratio of 3.14), and a
mirrored or flipped camera or sky puts the difference of the images far above their noise."""

import pathlib
import sys

import pytest

from conftest import cli_path, unavailable

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1] / "bench"))
import render_vs_mitsuba as rvm  # noqa: E402


@pytest.fixture(scope="module")
def scalar():
    try:
        import mitsuba as mi
    except ImportError:
        unavailable("mitsuba is not installed")
    mi.set_variant("scalar_rgb")
    return mi


@pytest.mark.parametrize("name", ["lambert-point-lit", "lambert-sky-lit"])
def test_render_matches_mitsuba(scalar, cli, name):
    row = rvm.compare_case(scalar, cli_path(), name, size=32, spp=64, mitsuba_spp=256)
    # The sphere's interior (no silhouette pixel, whose anti-aliasing may part): unbiased
    # renderers agree within the standard error of the two means.
    for c in range(3):
        ratio, se = row["interior_ratio"][c], row["interior_se"][c]
        assert abs(ratio - 1.0) <= 5.0 * se, (name, c, ratio, se)
    # The whole image: unbiased images differ by their noise alone, E[rel RMSE²] = noise². The
    # two-seed noise estimate over 1024 pixels scatters by a few per cent, hence 1.5; a mirrored
    # camera or environment gives tens of per cent against ~1 % of noise.
    assert row["rel_rmse"] <= 1.5 * row["noise"], row
