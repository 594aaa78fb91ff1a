"""io/crs.py: a CRS named for people (its code or WKT, its own name, or one made up from the
projection and the body)."""

from rasterio.crs import CRS

from hillshade_rt.io import crs as crsmod


def test_body_name_within_two_per_mille():
    assert crsmod.body_name(6378137.0) == "the Earth"
    assert crsmod.body_name(1737400.0) == "the Moon"
    assert crsmod.body_name(1737400.0 * 1.0019) == "the Moon"
    assert crsmod.body_name(1737400.0 * 1.0021) is None
    assert crsmod.body_name(3389500.0) == "Mars"         # the mean radius: no "(mean)"
    assert crsmod.body_name(1.0e6) is None


def test_crs_string_code_or_wkt():
    assert crsmod.crs_string(None) is None
    assert crsmod.crs_string(CRS.from_epsg(32611)) == "EPSG:32611"
    moon = CRS.from_proj4("+proj=stere +lat_0=-90 +R=1737400 +units=m")
    s = crsmod.crs_string(moon)
    assert not s.startswith("EPSG:") and "1737400" in s


def test_crs_name_own_or_made_up():
    assert crsmod.crs_name(None) is None
    assert crsmod.crs_name(CRS.from_epsg(32611)) == "WGS 84 / UTM zone 11N"
    moon = CRS.from_proj4("+proj=stere +lat_0=-90 +R=1737400 +units=m")
    name = crsmod.crs_name(moon)
    assert "Stereographic" in name and name.endswith("on the Moon (sphere, R 1737400 m)"), name
    ell = CRS.from_proj4("+proj=tmerc +a=3396190 +rf=169.894447 +units=m")
    name = crsmod.crs_name(ell)
    assert "on Mars" in name and "1/f 169.894" in name, name
