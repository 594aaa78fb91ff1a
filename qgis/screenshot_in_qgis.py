"""Run inside QGIS (``qgis --code qgis/screenshot_in_qgis.py``, started by
qgis/docs_screenshot.py under Xvfb): the plugin's Hillshade and Shadow mask algorithms on the DEM,
their outputs on the map (the shadow mask in translucent blue over the shaded relief), the
Processing Toolbox filtered to hillshade-rt, the Shadow mask dialog open; then a picture of the
screen to $HRT_SHOT_PNG and QGIS quits. $HRT_SHOT_DEM: the DEM; $HRT_SHOT_DIR: a scratch folder;
$HRT_SHOT_LOG: what happened (the driver prints it)."""

import os
import traceback

from qgis.core import QgsProject, QgsRasterLayer
from qgis.PyQt.QtCore import QTimer
from qgis.PyQt.QtWidgets import QApplication, QDockWidget, QSplitter
from qgis.utils import iface, plugins

DEM = os.environ["HRT_SHOT_DEM"]
SCRATCH = os.environ["HRT_SHOT_DIR"]
PNG = os.environ["HRT_SHOT_PNG"]
LOG = os.environ["HRT_SHOT_LOG"]
SUN = {"AZIMUTH": 225.0, "ELEVATION": 18.0}
state = {}


def log(text):
    with open(LOG, "a") as f:
        f.write(text + "\n")


def quit_qgis():
    QgsProject.instance().setDirty(False)
    QApplication.instance().exit(0)


def prepare():
    import processing
    relief = processing.run("hillshade_rt:hillshade", {
        "INPUT": DEM, **SUN, "AMBIENT": 0.25,
        "OUTPUT": os.path.join(SCRATCH, "relief.tif")})["OUTPUT"]
    # loaded by Processing itself, styled by the plugin (translucent blue shadow)
    mask = processing.runAndLoadResults("hillshade_rt:shadow", {
        "INPUT": DEM, **SUN, "OUTPUT": os.path.join(SCRATCH, "shadow.tif")})["OUTPUT"]
    log(f"computed {relief} and {mask}")
    base = QgsRasterLayer(relief, "hillshade-rt hillshade (az 225, el 18)")
    shadow = QgsProject.instance().mapLayersByName("Shadow mask")[0]
    log(f"shadow mask loaded with the renderer {shadow.renderer().type()}")
    shadow.setName("hillshade-rt shadow mask")
    project = QgsProject.instance()
    project.setCrs(base.crs())
    project.addMapLayer(base, False)
    project.layerTreeRoot().insertLayer(1, base)     # below the shadow mask
    window = iface.mainWindow()
    screen = QApplication.primaryScreen().geometry()
    window.setGeometry(screen)                 # no window manager under Xvfb: no maximize
    for dock in window.findChildren(QDockWidget):
        if dock.objectName() == "Browser":
            dock.hide()
    processing_plugin = plugins["processing"]
    processing_plugin.toolboxAction.setChecked(True)
    processing_plugin.toolbox.searchBox.setText("hillshade-rt")
    # the DEM on the left part of the map: the dialog stands on the right part
    extent = base.extent()
    extent.setXMaximum(extent.xMaximum() + 0.75 * extent.width())
    iface.mapCanvas().setExtent(extent)
    iface.mapCanvas().refresh()
    dialog = processing.createAlgorithmDialog("hillshade_rt:shadow", {
        "INPUT": DEM, **SUN, "ALGORITHM": "auto"})
    state["dialog"] = dialog
    for splitter in dialog.findChildren(QSplitter):
        splitter.setSizes([1, 0])              # the parameters only, not the help
    width, height = 480, 600
    dialog.setGeometry(screen.right() - 330 - width, screen.bottom() - 40 - height, width,
                       height)
    dialog.show()


def step_prepare():
    try:
        prepare()
        QTimer.singleShot(6000, step_shoot)
    except Exception:
        log(traceback.format_exc())
        quit_qgis()


def step_shoot():
    try:
        screen = QApplication.primaryScreen()
        picture = screen.grabWindow(0)
        log(f"screen {picture.width()}x{picture.height()} saved: {picture.save(PNG, 'PNG')}")
    except Exception:
        log(traceback.format_exc())
    if "dialog" in state:
        state["dialog"].close()
    QTimer.singleShot(200, quit_qgis)


QTimer.singleShot(3000, step_prepare)
