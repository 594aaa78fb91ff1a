"""hillshade-rt for QGIS: a Processing provider whose algorithms run the ``hillshade-rt``
program as a child process (the plugin never imports hillshade_rt or numba into QGIS's
Python; see commands.py)."""


def classFactory(iface):  # noqa: N802 (QGIS's name)
    """QGIS's entry point for the plugin."""
    from .plugin import HillshadeRtPlugin
    return HillshadeRtPlugin(iface)
