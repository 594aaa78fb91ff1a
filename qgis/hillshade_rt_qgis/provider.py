"""The hillshade-rt Processing provider: its algorithms and its one setting, the path of the
``hillshade-rt`` program (Settings > Options > Processing > Providers > hillshade-rt)."""

import os

from qgis.core import QgsProcessingProvider
from qgis.PyQt.QtGui import QIcon

from .commands import SETTING_PROGRAM

PROVIDER_ID = "hillshade_rt"


class HillshadeRtProvider(QgsProcessingProvider):

    def load(self):
        from processing.core.ProcessingConfig import ProcessingConfig, Setting
        ProcessingConfig.settingIcons[self.name()] = self.icon()
        ProcessingConfig.addSetting(Setting(
            self.name(), SETTING_PROGRAM,
            self.tr("hillshade-rt executable (empty: hillshade-rt on PATH, then ~/.local/bin)"),
            "", valuetype=Setting.FILE))
        ProcessingConfig.readSettings()
        self.refreshAlgorithms()
        return True

    def unload(self):
        from processing.core.ProcessingConfig import ProcessingConfig
        if SETTING_PROGRAM in ProcessingConfig.settings:
            ProcessingConfig.removeSetting(SETTING_PROGRAM)

    def loadAlgorithms(self):  # noqa: N802
        from .algorithms import ALGORITHMS
        for cls in ALGORITHMS:
            self.addAlgorithm(cls())

    def id(self):
        return PROVIDER_ID

    def name(self):
        return "hillshade-rt"

    def longName(self):  # noqa: N802
        return self.tr("hillshade-rt: terrain shadows, sun hours, sky view, horizons, irradiance")

    def icon(self):
        return QIcon(os.path.join(os.path.dirname(__file__), "icon.svg"))

    def supportedOutputRasterLayerExtensions(self):  # noqa: N802
        # what the program writes through GDAL; GeoTIFF first (the default)
        return ["tif", "tiff"]

    def supportedOutputVectorLayerExtensions(self):  # noqa: N802
        # the shadow polygons (shadow --vector): the formats the program writes
        return ["gpkg", "geojson", "fgb"]

    def defaultVectorFileExtension(self, hasGeometry=True):  # noqa: N802
        return "gpkg"
