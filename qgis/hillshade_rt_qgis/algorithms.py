"""The Processing algorithms: each maps its parameters to one ``hillshade-rt`` command line
(commands.py) and runs it as a child process; the program's stderr goes to the feedback, a
non-zero exit status raises QgsProcessingException with the program's one-line error, and
cancelling terminates the child (which leaves no output behind)."""

import os
import uuid

from qgis.core import (QgsCoordinateTransform, QgsPalettedRasterRenderer, QgsProcessing,
                       QgsProcessingAlgorithm, QgsProcessingException, QgsProcessingFeedback,
                       QgsProcessingLayerPostProcessorInterface,
                       QgsProcessingParameterBand, QgsProcessingParameterBoolean,
                       QgsProcessingParameterDateTime, QgsProcessingParameterDefinition,
                       QgsProcessingParameterEnum, QgsProcessingParameterFeatureSource,
                       QgsProcessingParameterField, QgsProcessingParameterFile,
                       QgsProcessingParameterFileDestination, QgsProcessingParameterNumber,
                       QgsProcessingParameterRasterDestination,
                       QgsProcessingParameterRasterLayer, QgsProcessingParameterString,
                       QgsProcessingParameterVectorDestination, QgsProcessingUtils)
from qgis.PyQt.QtCore import QCoreApplication
from qgis.PyQt.QtGui import QColor

from . import commands

SUN_LABELS = ("Azimuth and elevation", "Date and time (in the time zone below)")
SERIES_LABEL = "A series: from the date and time to the end, every step"
TABLE_FILTER = "CSV (*.csv);;GeoJSON (*.geojson);;JSON (*.json)"
ANIMATION_FILTER = "GIF animation (*.gif);;MP4 video (*.mp4)"


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
    # the output: a raster layer, or a file of this filter (a table, an animation)
    OUTPUT_FILTER = None

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

    def add_sun(self, series=False):
        """SUN (0 azimuth and elevation, 1 a date and time, 2 with ``series``: a series up to
        END_DATETIME every STEP minutes), AZIMUTH, ELEVATION, DATETIME, TIMEZONE."""
        labels = list(SUN_LABELS) + ([SERIES_LABEL] if series else [])
        self.addParameter(QgsProcessingParameterEnum(
            "SUN", self.tr("The sun from"), [self.tr(s) for s in labels], defaultValue=0))
        self.addParameter(QgsProcessingParameterNumber(
            "AZIMUTH", self.tr("Sun azimuth (degrees clockwise from north)"),
            QgsProcessingParameterNumber.Double, 315.0, minValue=-360.0, maxValue=720.0))
        self.addParameter(QgsProcessingParameterNumber(
            "ELEVATION", self.tr("Sun elevation (degrees above the horizon)"),
            QgsProcessingParameterNumber.Double, 45.0, minValue=0.0, maxValue=90.0))
        self.addParameter(QgsProcessingParameterDateTime(
            "DATETIME", self.tr("Date and time (local time in the time zone)"),
            QgsProcessingParameterDateTime.DateTime, optional=True))
        if series:
            self.add_series_end()
        self.add_zone("UTC")

    def add_series_end(self, step=60.0):
        self.addParameter(QgsProcessingParameterDateTime(
            "END_DATETIME", self.tr("Series: last date and time (local time in the time zone)"),
            QgsProcessingParameterDateTime.DateTime, optional=True))
        self.add_step(step, "Series: step (minutes)")

    def add_step(self, default, text="Step (minutes)"):
        self.addParameter(QgsProcessingParameterNumber(
            "STEP", self.tr(text), QgsProcessingParameterNumber.Double, default,
            minValue=0.1, maxValue=1440.0))

    def add_dates(self, end_text="End date (a range of days, included)"):
        self.addParameter(QgsProcessingParameterDateTime(
            "DATE", self.tr("Date"), QgsProcessingParameterDateTime.Date))
        self.addParameter(QgsProcessingParameterDateTime(
            "END_DATE", self.tr(end_text), QgsProcessingParameterDateTime.Date, optional=True))

    def add_height(self, text="Height above the ground (m)"):
        self.addParameter(QgsProcessingParameterNumber(
            "HEIGHT_ABOVE_GROUND", self.tr(text), QgsProcessingParameterNumber.Double, 0.0,
            minValue=0.0))

    def add_points(self):
        """POINTS (a point layer, any CRS: moved into the DEM's) and ID_FIELD (their names in
        the table; empty: the feature ids)."""
        self.addParameter(QgsProcessingParameterFeatureSource(
            "POINTS", self.tr("Points"), [QgsProcessing.TypeVectorPoint]))
        self.addParameter(QgsProcessingParameterField(
            "ID_FIELD", self.tr("Point names from the field (empty: feature ids)"),
            parentLayerParameterName="POINTS", optional=True))

    def add_zone(self, default):
        self.addParameter(QgsProcessingParameterString(
            "TIMEZONE", self.tr("Time zone (IANA name, e.g. Europe/Zurich)"), default,
            optional=True))

    def add_algorithm(self):
        self.addParameter(QgsProcessingParameterEnum(
            "ALGORITHM", self.tr("Algorithm"), list(commands.ALGORITHMS), defaultValue="auto",
            usesStaticStrings=True))

    def add_monthly(self, text):
        self.addParameter(QgsProcessingParameterBoolean("MONTHLY", self.tr(text), False))

    def optional_number(self, parameters, context, name):
        """An optional number parameter: None when not set."""
        if parameters.get(name) in (None, ""):
            return None
        return self.parameterAsDouble(parameters, name, context)

    def raster_file(self, parameters, context, name, what):
        """An optional raster layer parameter as the program reads it (a GDAL file name);
        None when not set."""
        if parameters.get(name) in (None, ""):
            return None
        layer = self.parameterAsRasterLayer(parameters, name, context)
        if layer is None:
            raise QgsProcessingException(self.tr("{} could not be opened").format(what))
        if layer.providerType() != "gdal":
            raise QgsProcessingException(self.tr(
                "{} must be a raster read through GDAL (a file), not a {} "
                "layer").format(what, layer.providerType()))
        return layer.source()

    def add_soft(self, text):
        self.addParameter(QgsProcessingParameterBoolean("SOFT", self.tr(text), False))

    def add_tail(self):
        """EXTRA (advanced) and OUTPUT: a raster, or a file of OUTPUT_FILTER."""
        extra = QgsProcessingParameterString(
            "EXTRA", self.tr("Additional hillshade-rt options (e.g. --no-earth-curvature "
                             "--threads 4)"), "", optional=True)
        extra.setFlags(extra.flags() | QgsProcessingParameterDefinition.FlagAdvanced)
        self.addParameter(extra)
        if self.OUTPUT_FILTER is None:
            self.addParameter(QgsProcessingParameterRasterDestination(
                "OUTPUT", self.tr(self.OUTPUT_LABEL)))
        else:
            self.addParameter(QgsProcessingParameterFileDestination(
                "OUTPUT", self.tr(self.OUTPUT_LABEL), self.tr(self.OUTPUT_FILTER)))

    # -- values
    def dem_layer(self, parameters, context):
        layer = self.parameterAsRasterLayer(parameters, "INPUT", context)
        if layer is None:
            raise QgsProcessingException(self.tr("the DEM could not be opened"))
        if layer.providerType() != "gdal":
            raise QgsProcessingException(self.tr(
                "the DEM must be a raster read through GDAL (a file), not a "
                "{} layer").format(layer.providerType()))
        return layer

    def dem(self, parameters, context):
        return self.dem_layer(parameters, context).source()

    def output(self, parameters, context, name="OUTPUT"):
        if self.OUTPUT_FILTER is None or name != "OUTPUT":
            return self.parameterAsOutputLayer(parameters, name, context)
        return self.parameterAsFileOutput(parameters, name, context)

    def common(self, parameters, context):
        """The keywords every command takes: the DEM, band, output, extra options."""
        return dict(dem=self.dem(parameters, context),
                    output=self.output(parameters, context),
                    band=self.parameterAsInt(parameters, "BAND", context) or 1,
                    extra=commands.split_extra(
                        self.parameterAsString(parameters, "EXTRA", context)))

    def when(self, parameters, context, name):
        """A date and time parameter as the command line writes it (None when not set)."""
        t = self.parameterAsDateTime(parameters, name, context)
        return t.toString("yyyy-MM-ddTHH:mm:ss") if t is not None and t.isValid() else None

    def day(self, parameters, context, name):
        d = self.parameterAsDateTime(parameters, name, context)
        return d.date().toString("yyyy-MM-dd") if d is not None and d.isValid() else None

    def number(self, parameters, context, name):
        return self.parameterAsDouble(parameters, name, context)

    def flag(self, parameters, context, name):
        return self.parameterAsBoolean(parameters, name, context)

    def points_file(self, parameters, context):
        """The POINTS as the --points CSV (id,x,y in the DEM's CRS) in Processing's temporary
        folder; every vertex of a multipoint is a point."""
        source = self.parameterAsSource(parameters, "POINTS", context)
        if source is None:
            raise QgsProcessingException(self.tr("the points could not be opened"))
        crs = self.dem_layer(parameters, context).crs()
        field = self.parameterAsString(parameters, "ID_FIELD", context)
        to_dem = (QgsCoordinateTransform(source.sourceCrs(), crs, context.transformContext())
                  if crs.isValid() and source.sourceCrs().isValid()
                  and source.sourceCrs() != crs else None)

        def points():
            for f in source.getFeatures():
                geom = f.geometry()
                if geom is None or geom.isEmpty():
                    continue
                if to_dem is not None:
                    geom.transform(to_dem)
                name = f[field] if field else f.id()
                for k, v in enumerate(geom.vertices()):
                    yield (name if k == 0 else f"{name}_{k}"), v.x(), v.y()
        path = os.path.join(QgsProcessingUtils.tempFolder(),
                            f"hillshade_rt_points_{uuid.uuid4().hex}.csv")
        try:
            commands.write_points_csv(path, points())
        except commands.ProgramError as e:
            raise QgsProcessingException(str(e))
        return path

    def sun(self, parameters, context):
        """sun=..., azimuth, elevation, time_, tz of the sun parameters (and end_time,
        step_minutes of a series)."""
        mode = commands.QUERY_SUN_MODES[self.parameterAsEnum(parameters, "SUN", context)]
        sun = dict(sun=mode, azimuth=self.number(parameters, context, "AZIMUTH"),
                   elevation=self.number(parameters, context, "ELEVATION"),
                   time_=self.when(parameters, context, "DATETIME"),
                   tz=self.parameterAsString(parameters, "TIMEZONE", context))
        if mode == "series":
            sun.update(end_time=self.when(parameters, context, "END_DATETIME"),
                       step_minutes=self.number(parameters, context, "STEP"))
        return sun

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
            argv = commands.with_progress(self.command(program, parameters, context))
        except commands.ProgramError as e:
            raise QgsProcessingException(str(e))
        feedback.pushCommandInfo(commands.quote(argv))

        def on_line(line):
            percent = commands.parse_progress(line)
            if percent is not None:             # {"progress": F}: the progress bar
                feedback.setProgress(percent)
            # its one-line error becomes the algorithm's error (below): not shown twice
            elif line.strip() and not commands.is_error_line(line):
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
        output = self.output(parameters, context)
        self.style_output(output, parameters, context)
        return dict(self.more_outputs(parameters, context), OUTPUT=output)

    def more_outputs(self, parameters, context):
        """Outputs besides OUTPUT (name -> path)."""
        return {}

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
            "sun. <b>Shadow polygons</b> (optional): the shadow as polygons in the DEM's CRS "
            "(GeoPackage, GeoJSON or FlatGeobuf), each with the sun's azimuth and elevation "
            "(and time); not with soft shadows.</p>")

    def initAlgorithm(self, config=None):  # noqa: N802
        self.add_dem()
        self.add_sun()
        self.add_algorithm()
        self.add_soft("Soft shadows (visible fraction of the sun's disk)")
        self.addParameter(QgsProcessingParameterBoolean(
            "SELF_SHADOW", self.tr("Also shadow cells facing away from the sun"), False))
        self.add_tail()
        vector = QgsProcessingParameterVectorDestination(
            "VECTOR", self.tr("Shadow polygons"), QgsProcessing.TypeVectorPolygon,
            optional=True, createByDefault=False)
        # a file the program writes (not a memory layer), of a format it writes
        vector.setSupportsNonFileBasedOutput(False)
        self.addParameter(vector)

    def vector(self, parameters, context):
        if parameters.get("VECTOR") in (None, ""):
            return None
        return self.parameterAsOutputLayer(parameters, "VECTOR", context) or None

    def more_outputs(self, parameters, context):
        vector = self.vector(parameters, context)
        return {"VECTOR": vector} if vector else {}

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
            self_shadow=self.parameterAsBoolean(parameters, "SELF_SHADOW", context),
            vector=self.vector(parameters, context))


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
            "longitude). <b>Monthly</b>: also the hours of each month of the period, one band "
            "per month after the total (its description YYYY-MM).</p>")

    def initAlgorithm(self, config=None):  # noqa: N802
        self.add_dem()
        self.add_dates()
        self.add_step(10.0)
        self.add_zone("")
        self.add_monthly("Also one band per month (the hours of each month)")
        self.add_algorithm()
        self.add_soft("Soft shadows (count the visible fraction of the sun's disk)")
        self.add_tail()

    def command(self, program, parameters, context):
        return commands.sun_hours_argv(
            program, **self.common(parameters, context),
            date=self.day(parameters, context, "DATE"),
            end_date=self.day(parameters, context, "END_DATE"),
            step_minutes=self.parameterAsDouble(parameters, "STEP", context),
            tz=self.parameterAsString(parameters, "TIMEZONE", context),
            monthly=self.flag(parameters, context, "MONTHLY"),
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


class HorizonAlgorithm(HillshadeRtAlgorithm):
    NAME = "horizon"
    DISPLAY = "Horizon angle"
    OUTPUT_LABEL = "Horizon angles"
    HELP = ("<p>The horizon angle of every cell (<code>hillshade-rt horizon</code>; float32 "
            "degrees above the horizontal, -9999 nodata; -90: no terrain ahead) toward one "
            "azimuth (one band), or toward each of N equally spaced azimuths, north first "
            "(one band each, its description the azimuth), or, as GRASS r.horizon, every "
            "<i>step</i> degrees from the <i>start</i> azimuth up to (not including) the "
            "<i>end</i> (empty: a whole turn), one band each; azimuths clockwise from north "
            "(r.horizon's start counts counter-clockwise from east: ours is 90 - its). A cell is "
            "lit by a sun at that azimuth iff its angle is at most the sun's elevation. Angles "
            "in degrees, or radians as r.horizon writes them. <b>Distance</b>: also the "
            "ground distance in metres to each horizon point (the same bands). scan is exact; "
            "hull approximates, faster.</p>")

    def initAlgorithm(self, config=None):  # noqa: N802
        self.add_dem()
        self.addParameter(QgsProcessingParameterEnum(
            "MODE", self.tr("Horizon toward"),
            [self.tr("One azimuth"), self.tr("N directions (one band each)"),
             self.tr("Start to end every step (r.horizon; one band each)")], defaultValue=0))
        self.addParameter(QgsProcessingParameterNumber(
            "AZIMUTH", self.tr("Azimuth (degrees clockwise from north)"),
            QgsProcessingParameterNumber.Double, 180.0, minValue=-360.0, maxValue=720.0))
        self.addParameter(QgsProcessingParameterNumber(
            "DIRECTIONS", self.tr("Directions"), QgsProcessingParameterNumber.Integer, 32,
            minValue=8, maxValue=360))
        self.addParameter(QgsProcessingParameterNumber(
            "START", self.tr("Start to end: first azimuth (degrees clockwise from north)"),
            QgsProcessingParameterNumber.Double, 0.0, minValue=-360.0, maxValue=720.0))
        self.addParameter(QgsProcessingParameterNumber(
            "END", self.tr("Start to end: azimuths before this one (degrees; empty: the start "
                           "+ 360)"),
            QgsProcessingParameterNumber.Double, None, optional=True, minValue=-360.0,
            maxValue=1080.0))
        self.addParameter(QgsProcessingParameterNumber(
            "STEP", self.tr("Start to end: step (degrees)"),
            QgsProcessingParameterNumber.Double, 15.0, minValue=0.01, maxValue=360.0))
        self.addParameter(QgsProcessingParameterEnum(
            "ANGLE_UNIT", self.tr("Unit of the angles written"), list(commands.ANGLE_UNITS),
            defaultValue="degrees", usesStaticStrings=True))
        self.addParameter(QgsProcessingParameterEnum(
            "METHOD", self.tr("Method"), list(commands.HORIZON_METHODS), defaultValue="scan",
            usesStaticStrings=True))
        self.addParameter(QgsProcessingParameterNumber(
            "MAX_DISTANCE", self.tr("Maximum distance (m, 0: the whole DEM)"),
            QgsProcessingParameterNumber.Double, 0.0, minValue=0.0))
        self.add_height()
        self.add_tail()
        self.addParameter(QgsProcessingParameterRasterDestination(
            "DISTANCE", self.tr("Distance to the horizon (m)"), optional=True,
            createByDefault=False))

    def distance(self, parameters, context):
        if parameters.get("DISTANCE") in (None, ""):
            return None
        return self.parameterAsOutputLayer(parameters, "DISTANCE", context) or None

    def more_outputs(self, parameters, context):
        distance = self.distance(parameters, context)
        return {"DISTANCE": distance} if distance else {}

    def command(self, program, parameters, context):
        return commands.horizon_argv(
            program, **self.common(parameters, context),
            mode=commands.HORIZON_MODES[self.parameterAsEnum(parameters, "MODE", context)],
            azimuth=self.number(parameters, context, "AZIMUTH"),
            directions=self.parameterAsInt(parameters, "DIRECTIONS", context),
            start=self.number(parameters, context, "START"),
            end=self.optional_number(parameters, context, "END"),
            step=self.number(parameters, context, "STEP"),
            angle_unit=self.parameterAsEnumString(parameters, "ANGLE_UNIT", context)
            or "degrees",
            distance=self.distance(parameters, context),
            method=self.parameterAsEnumString(parameters, "METHOD", context) or "scan",
            max_distance=self.number(parameters, context, "MAX_DISTANCE"),
            height_above_ground=self.number(parameters, context, "HEIGHT_ABOVE_GROUND"))


class ProfileAlgorithm(HillshadeRtAlgorithm):
    NAME = "profile"
    DISPLAY = "Horizon profile at points"
    OUTPUT_LABEL = "Horizon profiles (table)"
    OUTPUT_FILTER = TABLE_FILTER
    HELP = ("<p>The horizon profile of each point (<code>hillshade-rt profile</code>): the "
            "horizon elevation and the distance to it every <i>step</i> degrees of azimuth, "
            "clockwise from north, as a table: CSV (one row per point and azimuth; its first "
            "lines, starting with #, state the conventions), JSON or GeoJSON (one feature per "
            "point), by the file's extension. The points may be in any CRS.</p>")

    def initAlgorithm(self, config=None):  # noqa: N802
        self.add_dem()
        self.add_points()
        self.addParameter(QgsProcessingParameterNumber(
            "STEP", self.tr("Step (degrees of azimuth)"), QgsProcessingParameterNumber.Double,
            1.0, minValue=0.01, maxValue=90.0))
        self.add_height("Observer's height above the ground (m)")
        self.add_tail()

    def command(self, program, parameters, context):
        return commands.profile_argv(
            program, **self.common(parameters, context),
            points=self.points_file(parameters, context),
            step=self.number(parameters, context, "STEP"),
            height_above_ground=self.number(parameters, context, "HEIGHT_ABOVE_GROUND"))


class QueryAlgorithm(HillshadeRtAlgorithm):
    NAME = "query"
    DISPLAY = "Sun at points (query)"
    OUTPUT_LABEL = "Sun at the points (table)"
    OUTPUT_FILTER = TABLE_FILTER
    HELP = ("<p>Whether the sun reaches each point (<code>hillshade-rt query</code>): for each "
            "point and sun, lit or not, the sun's azimuth and elevation, the horizon toward "
            "the sun and the margin between them, as a table: CSV (one row per point and sun; "
            "its first lines, starting with #, state the conventions), JSON or GeoJSON, by the "
            "file's extension. The sun by azimuth and elevation, from a date and time, or a "
            "series of times every <i>step</i> minutes (local times in the time zone). "
            "<b>Irradiance</b>: also the clear-sky DNI and the direct beam on a horizontal "
            "surface (suns from times).</p>")

    def initAlgorithm(self, config=None):  # noqa: N802
        self.add_dem()
        self.add_points()
        self.add_sun(series=True)
        self.add_height("Observer's height above the ground (m)")
        self.addParameter(QgsProcessingParameterBoolean(
            "IRRADIANCE", self.tr("Also the clear-sky direct irradiance (suns from times)"),
            False))
        self.add_tail()

    def command(self, program, parameters, context):
        return commands.query_argv(
            program, **self.common(parameters, context), **self.sun(parameters, context),
            points=self.points_file(parameters, context),
            height_above_ground=self.number(parameters, context, "HEIGHT_ABOVE_GROUND"),
            irradiance=self.flag(parameters, context, "IRRADIANCE"))


class IrradianceAlgorithm(HillshadeRtAlgorithm):
    NAME = "irradiance"
    DISPLAY = "Irradiance"
    OUTPUT_LABEL = "Irradiance"
    HELP = ("<p>The beam, diffuse, reflected and global irradiance of every cell over a day or "
            "a range of days (<code>hillshade-rt irradiance</code>): 4 float32 bands, Wh/m2 "
            "(W/m2 with <i>mean</i>), -9999 nodata. Beam: DNI on the tilted surface, 0 in cast "
            "shadow; diffuse: DHI x the sky view factor (isotropic, or Perez); reflected: GHI x "
            "albedo x the terrain's view factor. A clear sky (pvlib's Ineichen or Haurwitz), "
            "or a measured one: a CSV of time, ghi (and dni, dhi) in W/m2. The Linke turbidity "
            "and the albedo: a number, or 12 monthly numbers (January first; each sample takes "
            "its month's); either also a raster (resampled to the DEM's grid; it must "
            "cover the DEM), which overrides the numbers: a Linke raster gives each cell its "
            "own clear sky. <b>Clear-sky indices</b> of the beam and the diffuse (0..1, "
            "GRASS r.sun's coeff_bh and coeff_dh; a number or a raster; not with a measured "
            "sky): the real sky's beam and diffuse are the clear sky's times them. "
            "<b>Monthly</b>: also the global "
            "energy of each month, one band per month after the four (description YYYY-MM). "
            "<b>Daily mean</b>: Wh/m2 per day instead of the period's Wh/m2. <b>Instants</b> "
            "(comma-separated, e.g. 2026-06-21T09:00, 2026-06-21T15:30, or times of day such "
            "as 09:00, 12:00 on the date; local times in the time zone): instead of the "
            "period, the four in W/m2 and the sun's angle above each cell's surface at each "
            "instant, 5 bands per instant (GRASS r.sun's mode 1).</p>")

    def initAlgorithm(self, config=None):  # noqa: N802
        self.add_dem()
        self.add_dates()
        self.add_step(15.0)
        self.add_zone("")
        self.addParameter(QgsProcessingParameterString(
            "TIMES", self.tr("Instants instead of the period: date-times or times of day on "
                             "the date, comma-separated (5 bands each)"), "", optional=True))
        self.addParameter(QgsProcessingParameterEnum(
            "CLEAR_SKY", self.tr("Clear sky"), list(commands.CLEAR_SKIES),
            defaultValue="ineichen", usesStaticStrings=True))
        self.addParameter(QgsProcessingParameterNumber(
            "LINKE_TURBIDITY", self.tr("Linke turbidity (0: pvlib's monthly climatology)"),
            QgsProcessingParameterNumber.Double, 0.0, minValue=0.0))
        self.addParameter(QgsProcessingParameterString(
            "LINKE_MONTHLY", self.tr("Linke turbidity by month: 12 numbers, January first "
                                     "(overrides the number)"), "", optional=True))
        self.addParameter(QgsProcessingParameterRasterLayer(
            "LINKE_RASTER", self.tr("Linke turbidity raster (1..10, covering the DEM; each "
                                    "cell's clear sky; overrides the numbers)"), optional=True))
        self.addParameter(QgsProcessingParameterNumber(
            "ALBEDO", self.tr("Albedo (ground reflectance, 0..1)"),
            QgsProcessingParameterNumber.Double, 0.2, minValue=0.0, maxValue=1.0))
        self.addParameter(QgsProcessingParameterString(
            "ALBEDO_MONTHLY", self.tr("Albedo by month: 12 numbers, January first (overrides "
                                      "the number)"), "", optional=True))
        self.addParameter(QgsProcessingParameterRasterLayer(
            "ALBEDO_RASTER", self.tr("Albedo raster (0..1, covering the DEM; overrides the "
                                     "numbers)"), optional=True))
        for name, text in (("BEAM", "beam"), ("DIFFUSE", "diffuse")):
            self.addParameter(QgsProcessingParameterNumber(
                f"{name}_INDEX", self.tr(f"Clear-sky index of the {text} (0..1, r.sun's "
                                         f"coeff_{text[0]}h; empty: none; not with a measured "
                                         "sky)"),
                QgsProcessingParameterNumber.Double, None, optional=True, minValue=0.0,
                maxValue=1.0))
            self.addParameter(QgsProcessingParameterRasterLayer(
                f"{name}_INDEX_RASTER", self.tr(f"Clear-sky index raster of the {text} (0..1, "
                                                "covering the DEM; overrides the number)"),
                optional=True))
        self.addParameter(QgsProcessingParameterFile(
            "GHI", self.tr("Measured sky: CSV of time, ghi [, dni, dhi] (W/m2)"),
            extension="csv", optional=True))
        self.addParameter(QgsProcessingParameterBoolean(
            "MEAN", self.tr("Mean W/m2 over the period instead of Wh/m2"), False))
        self.addParameter(QgsProcessingParameterBoolean(
            "DAILY_MEAN", self.tr("Wh/m2 per day (the energy divided by the days) instead of "
                                  "Wh/m2"), False))
        self.add_monthly("Also one band per month (the global energy of each month)")
        self.addParameter(QgsProcessingParameterBoolean(
            "PEREZ", self.tr("Perez anisotropic sky"), False))
        self.addParameter(QgsProcessingParameterNumber(
            "SKYVIEW_DIRECTIONS", self.tr("Sky view directions"),
            QgsProcessingParameterNumber.Integer, 32, minValue=4, maxValue=360))
        self.add_height("Height of the receiving surface above the ground (m)")
        self.add_algorithm()
        self.add_soft("Soft shadows (the visible fraction of the sun's disk)")
        self.add_tail()

    def command(self, program, parameters, context):
        date = self.day(parameters, context, "DATE")
        return commands.irradiance_argv(
            program, **self.common(parameters, context),
            date=date,
            end_date=self.day(parameters, context, "END_DATE"),
            step_minutes=self.number(parameters, context, "STEP"),
            tz=self.parameterAsString(parameters, "TIMEZONE", context),
            times=commands.instants(self.parameterAsString(parameters, "TIMES", context),
                                    date),
            clear_sky=self.parameterAsEnumString(parameters, "CLEAR_SKY", context)
            or "ineichen",
            linke_turbidity=commands.sky_value(
                "the Linke turbidity by month",
                self.number(parameters, context, "LINKE_TURBIDITY") or None,
                self.parameterAsString(parameters, "LINKE_MONTHLY", context),
                self.raster_file(parameters, context, "LINKE_RASTER",
                                 "the Linke turbidity raster")),
            albedo=commands.sky_value(
                "the albedo by month", self.number(parameters, context, "ALBEDO"),
                self.parameterAsString(parameters, "ALBEDO_MONTHLY", context),
                self.raster_file(parameters, context, "ALBEDO_RASTER", "the albedo raster")),
            beam_index=commands.sky_value(
                "the beam index", self.optional_number(parameters, context, "BEAM_INDEX"),
                None, self.raster_file(parameters, context, "BEAM_INDEX_RASTER",
                                       "the beam index raster")),
            diffuse_index=commands.sky_value(
                "the diffuse index", self.optional_number(parameters, context, "DIFFUSE_INDEX"),
                None, self.raster_file(parameters, context, "DIFFUSE_INDEX_RASTER",
                                       "the diffuse index raster")),
            ghi=self.parameterAsFile(parameters, "GHI", context) or None,
            mean=self.flag(parameters, context, "MEAN"),
            daily_mean=self.flag(parameters, context, "DAILY_MEAN"),
            monthly=self.flag(parameters, context, "MONTHLY"),
            perez=self.flag(parameters, context, "PEREZ"),
            skyview_directions=self.parameterAsInt(parameters, "SKYVIEW_DIRECTIONS", context),
            height_above_ground=self.number(parameters, context, "HEIGHT_ABOVE_GROUND"),
            algorithm=self.algorithm(parameters, context),
            soft=self.flag(parameters, context, "SOFT"))


class AnimateAlgorithm(HillshadeRtAlgorithm):
    NAME = "animate"
    DISPLAY = "Animate shadows (GIF, MP4)"
    OUTPUT_LABEL = "Animation"
    OUTPUT_FILTER = ANIMATION_FILTER
    HELP = ("<p>An animation of the shadows over a day, from local midnight, or over a series "
            "of times (<code>hillshade-rt animate</code>): each frame the shaded relief lit by "
            "that time's sun, cast shadows tinted blue, dark at night, the local time written "
            "in a corner. A looping GIF, or an MP4 (needs the program's video extra: pip "
            "install 'hillshade-rt[video]'), by the file's extension. Times are local times in "
            "the time zone (empty: the zone of the DEM's centre).</p>")

    def initAlgorithm(self, config=None):  # noqa: N802
        self.add_dem()
        self.addParameter(QgsProcessingParameterEnum(
            "MODE", self.tr("Frames over"),
            [self.tr("A day (the date)"), self.tr("A series (start to end)")], defaultValue=0))
        self.addParameter(QgsProcessingParameterDateTime(
            "DATE", self.tr("Date"), QgsProcessingParameterDateTime.Date, optional=True))
        self.addParameter(QgsProcessingParameterDateTime(
            "DATETIME", self.tr("Series: first date and time"),
            QgsProcessingParameterDateTime.DateTime, optional=True))
        self.addParameter(QgsProcessingParameterDateTime(
            "END_DATETIME", self.tr("Series: last date and time"),
            QgsProcessingParameterDateTime.DateTime, optional=True))
        self.add_step(30.0, "Step between frames (minutes)")
        self.add_zone("")
        self.addParameter(QgsProcessingParameterNumber(
            "FPS", self.tr("Frames per second"), QgsProcessingParameterNumber.Double, 12.0,
            minValue=0.1, maxValue=50.0))
        self.addParameter(QgsProcessingParameterNumber(
            "SIZE", self.tr("Picture size (pixels on the long side, at most)"),
            QgsProcessingParameterNumber.Integer, 1024, minValue=16))
        self.addParameter(QgsProcessingParameterBoolean(
            "LABEL", self.tr("Write the date and time on each frame"), True))
        self.add_algorithm()
        self.add_tail()

    def command(self, program, parameters, context):
        return commands.animate_argv(
            program, **self.common(parameters, context),
            mode=commands.ANIMATE_MODES[self.parameterAsEnum(parameters, "MODE", context)],
            date=self.day(parameters, context, "DATE"),
            start=self.when(parameters, context, "DATETIME"),
            end=self.when(parameters, context, "END_DATETIME"),
            step_minutes=self.number(parameters, context, "STEP"),
            tz=self.parameterAsString(parameters, "TIMEZONE", context),
            fps=self.number(parameters, context, "FPS"),
            size=self.parameterAsInt(parameters, "SIZE", context),
            label=self.flag(parameters, context, "LABEL"),
            algorithm=self.algorithm(parameters, context))


class IlluminationAlgorithm(HillshadeRtAlgorithm):
    NAME = "illumination"
    DISPLAY = "Illumination over a subsolar series"
    OUTPUT_LABEL = "Illumination"
    HELP = ("<p>The illumination of every cell over a subsolar series "
            "(<code>hillshade-rt illumination</code>; float32, NaN nodata), each cell with its "
            "own sun on the body (the Moon, Mars, the Earth): band 1 the fraction of the time "
            "lit, [2 with soft shadows: the mean visible fraction of the sun's disk], then the "
            "longest continuous shadow (hours) and permanently shadowed (1 never lit). The "
            "series: a CSV of time,lat,lon[,distance_m] or a JPL Horizons table saved as "
            "CSV.</p>")

    def initAlgorithm(self, config=None):  # noqa: N802
        self.add_dem()
        self.addParameter(QgsProcessingParameterFile(
            "SUBSOLAR_FILE", self.tr("Subsolar series (CSV or JPL Horizons table)")))
        self.addParameter(QgsProcessingParameterString(
            "BODY", self.tr("Body: moon, mars, earth or a radius in metres (empty: the "
                            "CRS's)"), "", optional=True))
        self.addParameter(QgsProcessingParameterNumber(
            "SUN_DISTANCE", self.tr("The sun's distance (m; 0: the body's mean distance)"),
            QgsProcessingParameterNumber.Double, 0.0, minValue=0.0))
        self.add_height("Height of the lit point above every cell (m)")
        self.add_soft("Soft shadows (the visible fraction of the sun's disk)")
        self.add_tail()

    def command(self, program, parameters, context):
        return commands.illumination_argv(
            program, **self.common(parameters, context),
            subsolar_file=self.parameterAsFile(parameters, "SUBSOLAR_FILE", context),
            body=self.parameterAsString(parameters, "BODY", context),
            sun_distance=self.number(parameters, context, "SUN_DISTANCE"),
            height_above_ground=self.number(parameters, context, "HEIGHT_ABOVE_GROUND"),
            soft=self.flag(parameters, context, "SOFT"))


ALGORITHMS = (ShadowAlgorithm, SunHoursAlgorithm, SkyviewAlgorithm, HillshadeAlgorithm,
              HorizonAlgorithm, ProfileAlgorithm, IrradianceAlgorithm, QueryAlgorithm,
              AnimateAlgorithm, IlluminationAlgorithm)
