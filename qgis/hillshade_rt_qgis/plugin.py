"""The plugin: registers the hillshade-rt Processing provider (also under qgis_process, which
calls initProcessing of plugins whose metadata says hasProcessingProvider=yes)."""

from qgis.core import QgsApplication


class HillshadeRtPlugin:
    def __init__(self, iface):
        self.iface = iface
        self.provider = None

    def initProcessing(self):  # noqa: N802
        from .provider import HillshadeRtProvider
        if self.provider is None:
            self.provider = HillshadeRtProvider()
            QgsApplication.processingRegistry().addProvider(self.provider)

    def initGui(self):  # noqa: N802
        self.initProcessing()

    def unload(self):
        if self.provider is not None:
            QgsApplication.processingRegistry().removeProvider(self.provider)
            self.provider = None
