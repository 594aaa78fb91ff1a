"""Quick-look pictures: the colour ramp of continuous products and the horizon panorama."""

import numpy as np

from hillshade_rt.model.geometry import Grid
from hillshade_rt.pictures.preview import RAMP, panorama_rgb, ramp_colours, relief_rgb, scaled


def test_ramp_runs_from_its_first_to_its_last_colour():
    c = ramp_colours(np.array([-1.0, 0.0, 0.5, 1.0, 2.0, np.nan]))
    np.testing.assert_allclose(c[[0, 1, 5]], RAMP[[0, 0, 0]])
    np.testing.assert_allclose(c[2], RAMP[2])
    np.testing.assert_allclose(c[[3, 4]], RAMP[[-1, -1]])


def test_scaled_maps_the_given_range_and_defaults_to_percentiles():
    v = np.linspace(0.0, 100.0, 1001)
    np.testing.assert_allclose(scaled(v, 0.0, 100.0), v / 100.0, atol=1e-6)
    s = scaled(v)
    assert abs(s[20]) < 1e-6 and abs(s[980] - 1.0) < 1e-6


def test_relief_with_a_ramp_is_brighter_where_the_value_is_higher():
    z = np.zeros((20, 20), np.float32)
    v = np.zeros((20, 20), np.float32)
    v[:, 10:] = 1.0
    pic = relief_rgb(z, Grid.uniform(20, 20, 10.0), ramp=v).astype(int)
    assert pic[:, 10:].sum() > pic[:, :10].sum()
    assert (pic[:, 15] == pic[0, 15]).all()


def test_panorama_puts_the_sky_above_the_horizon_line():
    az = np.arange(0.0, 360.0, 10.0)
    ang = np.where((az >= 90) & (az < 180), 20.0, 5.0)       # a wall to the south-east
    pic = panorama_rgb(az, ang, low=-10.0, high=30.0, width=360, height=400)
    # rows: elevation 30 - (i + .5) * 0.1; column 45 looks at azimuth 45.5 (horizon 5 deg),
    # column 135 at 135.5 (20 deg)
    def is_sky(px):
        return px[2] > px[0]
    assert is_sky(pic[240, 45]) and not is_sky(pic[260, 45])      # 5.95 vs 3.95 deg
    assert is_sky(pic[90, 135]) and not is_sky(pic[110, 135])     # 20.95 vs 18.95 deg
