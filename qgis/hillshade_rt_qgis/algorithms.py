"""The Processing algorithms: each maps its parameters to one ``hillshade-rt`` command line
(commands.py) and runs it as a child process; the program's stderr goes to the feedback, a
non-zero exit status raises QgsProcessingException with the program's one-line error, and
cancelling terminates the child (which leaves no output behind)."""

from qgis.core import (QgsPalettedRasterRenderer, QgsProcessingAlgorithm,
                       QgsProcessingException, QgsProcessingFeedback,
                       QgsProcessingLayerPostProcessorInterface,
                       QgsProcessingParameterBand, QgsProcessingParameterBoolean,
                       QgsProcessingParameterDateTime, QgsProcessingParameterDefinition,
                       QgsProcessingParameterEnum, QgsProcessingParameterNumber,
                       QgsProcessingParameterRasterDestination,
                       QgsProcessingParameterRasterLayer, QgsProcessingParameterString)
from qgis.PyQt.QtCore import QCoreApplication
from qgis.PyQt.QtGui import QColor

from . import commands

SUN_LABELS = ("Azimuth and elevation", "Date and time (in the time zone below)")


class ShadowStyle(QgsProcessingLayerPostProcessorInterface):
    """The shadow mask as QGIS loads it: shadow translucent blue, lit cells transparent (255,
    nodata, is transparent already)."""

    def postProcessLayer(self, layer, context, feedback):  # noqa: N802
        renderer = QgsPalettedRasterRenderer(layer.dataProvider(), 1, [
            QgsPalettedRasterRenderer.Class(1, QColor(30, 70, 230, 120), "shadow"),
            QgsPalettedRasterRenderer.Class(0, QColor(0, 0, 0, 0), "lit")])
        layer.setRenderer(renderer)
        layer.triggerRepaint()


class HillshadeRtAlgorithm(QgsProcessingAlgorithm):
    """What the algorithms share: the DEM and its band, the sun, the algorithm, the extra
    options, the run of the program."""

    NAME = ""
    DISPLAY = ""
    HELP = ""
    OUTPUT_LABEL = "Output"

    def tr(self, text):
        return QCoreApplication.translate("HillshadeRt", text)

    def createInstance(self):  # noqa: N802
        return type(self)()

    def name(self):
        return self.NAME

    def displayName(self):  # noqa: N802
        return self.tr(self.DISPLAY)

    def group(self):
        return self.tr("Terrain lighting")

    def groupId(self):  # noqa: N802
        return "terrainlighting"

    def shortHelpString(self):  # noqa: N802
        return self.tr(self.HELP) + self.tr(
            "<p>Runs the <code>hillshade-rt</code> program (its path: Settings &gt; Options &gt; "
            "Processing &gt; Providers &gt; hillshade-rt; default: on PATH, then "
            "~/.local/bin). Its messages appear in the log; its one-line error, if it fails, "
            "is the algorithm's error.</p>")

    # -- parameters shared by the algorithms
    def add_dem(self):
        self.addParameter(QgsProcessingParameterRasterLayer("INPUT", self.tr("DEM")))
        self.addParameter(QgsProcessingParameterBand("BAND", self.tr("Band"), 1, "INPUT",
                                                     optional=True))

    def add_sun(self):
        self.addParameter(QgsProcessingParameterEnum(
            "SUN", self.tr("The sun from"), [self.tr(s) for s in SUN_LABELS], defaultValue=0))
        self.addParameter(QgsProcessingParameterNumber(
            "AZIMUTH", self.tr("Sun azimuth (degrees clockwise from north)"),
            QgsProcessingParameterNumber.Double, 315.0, minValue=-360.0, maxValue=720.0))
        self.addParameter(QgsProcessingParameterNumber(
            "ELEVATION", self.tr("Sun elevation (degrees above the horizon)"),
            QgsProcessingParameterNumber.Double, 45.0, minValue=0.0, maxValue=90.0))
        self.addParameter(QgsProcessingParameterDateTime(
            "DATETIME", self.tr("Date and time (local time in the time zone)"),
            QgsProcessingParameterDateTime.DateTime, optional=True))
        self.add_zone("UTC")

    def add_zone(self, default):
        self.addParameter(QgsProcessingParameterString(
            "TIMEZONE", self.tr("Time zone (IANA name, e.g. Europe/Zurich)"), default,
            optional=True))

    def add_algorithm(self):
        self.addParameter(QgsProcessingParameterEnum(
            "ALGORITHM", self.tr("Algorithm"), list(commands.ALGORITHMS), defaultValue="auto",
            usesStaticStrings=True))

    def add_soft(self, text):
        self.addParameter(QgsProcessingParameterBoolean("SOFT", self.tr(text), False))

    def add_tail(self):
        extra = QgsProcessingParameterString(
            "EXTRA", self.tr("Additional hillshade-rt options (e.g. --no-earth-curvature "
                             "--threads 4)"), "", optional=True)
        extra.setFlags(extra.flags() | QgsProcessingParameterDefinition.FlagAdvanced)
        self.addParameter(extra)
        self.addParameter(QgsProcessingParameterRasterDestination(
            "OUTPUT", self.tr(self.OUTPUT_LABEL)))

    # -- values
    def dem(self, parameters, context):
        layer = self.parameterAsRasterLayer(parameters, "INPUT", context)
        if layer is None:
            raise QgsProcessingException(self.tr("the DEM could not be opened"))
        if layer.providerType() != "gdal":
            raise QgsProcessingException(self.tr(
                "the DEM must be a raster read through GDAL (a file), not a "
                "{} layer").format(layer.providerType()))
        return layer.source()

    def common(self, parameters, context):
        """The keywords every command takes: the DEM, band, output, extra options."""
        return dict(dem=self.dem(parameters, context),
                    output=self.parameterAsOutputLayer(parameters, "OUTPUT", context),
                    band=self.parameterAsInt(parameters, "BAND", context) or 1,
                    extra=commands.split_extra(
                        self.parameterAsString(parameters, "EXTRA", context)))

    def sun(self, parameters, context):
        """sun=..., azimuth, elevation, time_, tz of the sun parameters."""
        mode = commands.SUN_MODES[self.parameterAsEnum(parameters, "SUN", context)]
        when = self.parameterAsDateTime(parameters, "DATETIME", context)
        return dict(sun=mode,
                    azimuth=self.parameterAsDouble(parameters, "AZIMUTH", context),
                    elevation=self.parameterAsDouble(parameters, "ELEVATION", context),
                    time_=(when.toString("yyyy-MM-ddTHH:mm:ss")
                           if when is not None and when.isValid() else None),
                    tz=self.parameterAsString(parameters, "TIMEZONE", context))

    def algorithm(self, parameters, context):
        return self.parameterAsEnumString(parameters, "ALGORITHM", context) or "auto"

    def command(self, program, parameters, context):
        """The program's argv for these parameters (each algorithm's own)."""
        raise NotImplementedError

    def processAlgorithm(self, parameters, context, feedback):  # noqa: N802
        from processing.core.ProcessingConfig import ProcessingConfig
        if feedback is None:
            feedback = QgsProcessingFeedback()
        try:
            program = commands.find_program(
                ProcessingConfig.getSetting(commands.SETTING_PROGRAM))
            argv = self.command(program, parameters, context)
        except commands.ProgramError as e:
            raise QgsProcessingException(str(e))
        feedback.pushCommandInfo(commands.quote(argv))

        def on_line(line):
            # its one-line error becomes the algorithm's error (below): not shown twice
            if line.strip() and not commands.is_error_line(line):
                feedback.pushInfo(line)
        try:
            result = commands.run(argv, on_line=on_line, is_canceled=feedback.isCanceled)
        except commands.ProgramError as e:
            raise QgsProcessingException(str(e))
        if result.canceled:
            raise QgsProcessingException(self.tr(
                "canceled: hillshade-rt was stopped (no output written)"))
        if result.returncode != 0:
            raise QgsProcessingException(result.error_line())
        feedback.setProgress(100)
        output = self.parameterAsOutputLayer(parameters, "OUTPUT", context)
        self.style_output(output, parameters, context)
        return {"OUTPUT": output}

    def style_output(self, output, parameters, context):
        """A style for the output when QGIS loads it (none: QGIS's default)."""


class ShadowAlgorithm(HillshadeRtAlgorithm):
    NAME = "shadow"
    DISPLAY = "Shadow mask"
    OUTPUT_LABEL = "Shadow mask"
    HELP = ("<p>The cast-shadow mask of the DEM (<code>hillshade-rt shadow</code>): 1 shadow, "
            "0 lit, 255 nodata (GeoTIFF, byte). The sun by azimuth and elevation, or from a "
            "date and time at the DEM's centre (the time is local time in the IANA time zone "
            "given, e.g. Europe/Zurich; UTC when empty). The exact algorithms (auto, bounds, "
            "brute, smap, horizon) give the same mask; sweep approximates. "
            "<b>Soft shadows</b>: the visible fraction of the sun's disk (float32, 1 fully lit, "
            "-9999 nodata) instead. <b>Self-shadow</b>: also shadow cells facing away from the "
            "sun.</p>")

    def initAlgorithm(self, config=None):  # noqa: N802
        self.add_dem()
        self.add_sun()
        self.add_algorithm()
        self.add_soft("Soft shadows (visible fraction of the sun's disk)")
        self.addParameter(QgsProcessingParameterBoolean(
            "SELF_SHADOW", self.tr("Also shadow cells facing away from the sun"), False))
        self.add_tail()

    def style_output(self, output, parameters, context):
        if (context.willLoadLayerOnCompletion(output)
                and not self.parameterAsBoolean(parameters, "SOFT", context)):
            # kept alive on the class: QGIS does not own a post-processor made in Python, and
            # it runs after this (cloned) algorithm may be gone
            ShadowStyle.instance = ShadowStyle()
            context.layerToLoadOnCompletionDetails(output).setPostProcessor(ShadowStyle.instance)

    def command(self, program, parameters, context):
        return commands.shadow_argv(
            program, **self.common(parameters, context), **self.sun(parameters, context),
            algorithm=self.algorithm(parameters, context),
            soft=self.parameterAsBoolean(parameters, "SOFT", context),
            self_shadow=self.parameterAsBoolean(parameters, "SELF_SHADOW", context))


class HillshadeAlgorithm(HillshadeRtAlgorithm):
    NAME = "hillshade"
    DISPLAY = "Hillshade (shaded relief with cast shadows)"
    OUTPUT_LABEL = "Shaded relief"
    HELP = ("<p>Shaded relief with cast shadows (<code>hillshade-rt hillshade</code>): "
            "ambient + (1 - ambient) x max(0, L.N) in lit cells, ambient in shadow (normals by "
            "Horn's method, like gdaldem), written as 1..255, 0 nodata. The sun as for Shadow "
            "mask (default azimuth 315, elevation 45, like gdaldem).</p>")

    def initAlgorithm(self, config=None):  # noqa: N802
        self.add_dem()
        self.add_sun()
        self.addParameter(QgsProcessingParameterNumber(
            "AMBIENT", self.tr("Ambient light (in shadow and on faces turned away, 0..1)"),
            QgsProcessingParameterNumber.Double, 0.2, minValue=0.0, maxValue=1.0))
        self.add_algorithm()
        self.add_soft("Soft shadows (penumbra from the sun's disk)")
        self.add_tail()

    def command(self, program, parameters, context):
        return commands.hillshade_argv(
            program, **self.common(parameters, context), **self.sun(parameters, context),
            ambient=self.parameterAsDouble(parameters, "AMBIENT", context),
            algorithm=self.algorithm(parameters, context),
            soft=self.parameterAsBoolean(parameters, "SOFT", context))


class SunHoursAlgorithm(HillshadeRtAlgorithm):
    NAME = "sunhours"
    DISPLAY = "Sun hours"
    OUTPUT_LABEL = "Sun hours"
    HELP = ("<p>Hours of direct sun per cell over a day, or a range of days up to the end "
            "date (<code>hillshade-rt sun-hours</code>; float32 hours, -9999 nodata). The sun "
            "every <i>step</i> minutes, each lit sample counting for its interval. Days run "
            "midnight to midnight in the time zone (empty: local mean solar time at the DEM's "
            "longitude).</p>")

    def initAlgorithm(self, config=None):  # noqa: N802
        self.add_dem()
        self.addParameter(QgsProcessingParameterDateTime(
            "DATE", self.tr("Date"), QgsProcessingParameterDateTime.Date))
        self.addParameter(QgsProcessingParameterDateTime(
            "END_DATE", self.tr("End date (a range of days, included)"),
            QgsProcessingParameterDateTime.Date, optional=True))
        self.addParameter(QgsProcessingParameterNumber(
            "STEP", self.tr("Step (minutes)"), QgsProcessingParameterNumber.Double, 10.0,
            minValue=0.1, maxValue=1440.0))
        self.add_zone("")
        self.add_algorithm()
        self.add_soft("Soft shadows (count the visible fraction of the sun's disk)")
        self.add_tail()

    def command(self, program, parameters, context):
        def day(name):
            d = self.parameterAsDateTime(parameters, name, context)
            return d.date().toString("yyyy-MM-dd") if d is not None and d.isValid() else None
        return commands.sun_hours_argv(
            program, **self.common(parameters, context), date=day("DATE"),
            end_date=day("END_DATE"),
            step_minutes=self.parameterAsDouble(parameters, "STEP", context),
            tz=self.parameterAsString(parameters, "TIMEZONE", context),
            algorithm=self.algorithm(parameters, context),
            soft=self.parameterAsBoolean(parameters, "SOFT", context))


class SkyviewAlgorithm(HillshadeRtAlgorithm):
    NAME = "skyview"
    DISPLAY = "Sky view factor"
    OUTPUT_LABEL = "Sky view factor"
    HELP = ("<p>The sky view factor of every cell (<code>hillshade-rt skyview</code>; float32 "
            "0..1, -9999 nodata) from its exact horizon in <i>directions</i> azimuths. "
            "zaksek: 1 - mean sine of the horizon elevation (as RVT); dozier: the "
            "cosine-weighted sky seen by the tilted surface. <i>Maximum distance</i> limits the "
            "search for the horizon (0: the whole DEM).</p>")

    def initAlgorithm(self, config=None):  # noqa: N802
        self.add_dem()
        self.addParameter(QgsProcessingParameterNumber(
            "DIRECTIONS", self.tr("Directions"), QgsProcessingParameterNumber.Integer, 32,
            minValue=4, maxValue=360))
        self.addParameter(QgsProcessingParameterEnum(
            "DEFINITION", self.tr("Definition"), list(commands.SKYVIEW_DEFINITIONS),
            defaultValue="zaksek", usesStaticStrings=True))
        self.addParameter(QgsProcessingParameterNumber(
            "MAX_DISTANCE", self.tr("Maximum distance (m, 0: the whole DEM)"),
            QgsProcessingParameterNumber.Double, 0.0, minValue=0.0))
        self.add_tail()

    def command(self, program, parameters, context):
        return commands.skyview_argv(
            program, **self.common(parameters, context),
            directions=self.parameterAsInt(parameters, "DIRECTIONS", context),
            definition=self.parameterAsEnumString(parameters, "DEFINITION", context)
            or "zaksek",
            max_distance=self.parameterAsDouble(parameters, "MAX_DISTANCE", context))


ALGORITHMS = (ShadowAlgorithm, SunHoursAlgorithm, SkyviewAlgorithm, HillshadeAlgorithm)
