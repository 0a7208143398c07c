"""The algorithms: a raster layer's band in, one float32 GeoTIFF out (the input's CRS and geotransform,
NoData -9999 where the input had none), baked by the Python module hfbake with the job keys' names and
checks; a bad value fails the algorithm with hfbake's message."""

import math
import os
import warnings

import numpy as np
from osgeo import gdal
from qgis.core import (
    QgsProcessingAlgorithm,
    QgsProcessingException,
    QgsProcessingParameterBand,
    QgsProcessingParameterNumber,
    QgsProcessingParameterRasterDestination,
    QgsProcessingParameterRasterLayer,
)

import hfbake


class _Bake(QgsProcessingAlgorithm):
    """One product: `method` baked with its `layer` (for per-direction layers: all directions, one band
    each); `radius_key` names the method's distance key, if it has one."""

    key = name_text = method = layer = ""
    radius_key = None
    default_directions = 16
    help_text = ""

    def name(self):
        return self.key

    def displayName(self):  # noqa: N802
        return self.name_text

    def shortHelpString(self):  # noqa: N802
        return self.help_text

    def createInstance(self):  # noqa: N802
        return type(self)()

    def initAlgorithm(self, config=None):  # noqa: N802
        self.addParameter(QgsProcessingParameterRasterLayer(
            "INPUT", "Elevation (projected CRS; heights in its unit unless the band declares one)"))
        self.addParameter(QgsProcessingParameterBand("BAND", "Band", 1, "INPUT"))
        self.addParameter(QgsProcessingParameterNumber("DIRECTIONS", "Directions", QgsProcessingParameterNumber.Integer,
                                                       self.default_directions, minValue=1, maxValue=4096))
        if self.radius_key:
            self.addParameter(QgsProcessingParameterNumber(
                "RADIUS", "Radius (map units; 0: the method's default)", QgsProcessingParameterNumber.Double, 0.0,
                minValue=0.0))
        self.addParameter(QgsProcessingParameterRasterDestination("OUTPUT", self.name_text))

    def processAlgorithm(self, parameters, context, feedback):  # noqa: N802
        layer = self.parameterAsRasterLayer(parameters, "INPUT", context)
        band_index = self.parameterAsInt(parameters, "BAND", context)
        output = self.parameterAsOutputLayer(parameters, "OUTPUT", context)
        folder = os.path.dirname(os.path.abspath(output))
        if not os.path.isdir(folder):
            raise QgsProcessingException(f"{output}: its folder does not exist")
        if os.path.isdir(output):
            raise QgsProcessingException(f"{output}: is a folder: name the GeoTIFF to write")
        # Never over what the input reads (the raster, a VRT's sources, its world or .aux.xml file).
        source = gdal.Open(layer.source()) if layer is not None else None
        for f in (source.GetFileList() or []) if source is not None else []:
            if os.path.exists(f) and os.path.exists(output) and os.path.samefile(f, output):
                raise QgsProcessingException(
                    f"{output}: is {f}, which the input layer reads: give the output another name")
        source = None
        # The checks and conversions a job naming the file gets (docs/python.md, read_dem), and the band's
        # declared scale and offset applied, as QGIS shows the band's values.
        try:
            dem = hfbake.read_dem(layer.source(), band_index, unscale=True)
        except hfbake.InputError as e:
            raise QgsProcessingException(str(e))
        for warning in dem.warnings:
            feedback.pushWarning(warning)
        keys = {"directions": self.parameterAsInt(parameters, "DIRECTIONS", context), "layers": [self.layer]}
        if self.radius_key:
            radius = self.parameterAsDouble(parameters, "RADIUS", context)
            if radius > 0:
                keys[self.radius_key] = radius
        keys.update(dem.keys)

        class Stop:  # the Cancel button, polled by hfbake while it bakes
            def is_set(self):
                return feedback.isCanceled()

        try:
            with warnings.catch_warnings(record=True) as said:  # the bake's warnings go to the log
                warnings.simplefilter("always")
                values = getattr(hfbake, self.method)(
                    dem.heights, progress=lambda f: feedback.setProgress(100 * f),
                    cancel=Stop(), **keys)[self.layer]
        except hfbake.InputError as e:
            raise QgsProcessingException(f"{self.method}: {e}")
        except hfbake.Cancelled:
            return {}
        for w in said:
            feedback.pushWarning(f"{layer.source()}: {w.message}")
        planes = values if values.ndim == 3 else values[np.newaxis]
        rows, columns = planes.shape[1:]
        # Written beside its name and renamed into place: whole or not at all.
        temporary = os.path.join(folder, f".{os.path.basename(output)}.tmp-{os.getpid()}.tif")
        gdal.ErrorReset()
        out = gdal.GetDriverByName("GTiff").Create(temporary, columns, rows, planes.shape[0], gdal.GDT_Float32,
                                                   options=["COMPRESS=DEFLATE", "TILED=YES"])
        if out is None:
            raise QgsProcessingException(f"{output}: GDAL cannot create it: {gdal.GetLastErrorMsg()}")
        out.SetGeoTransform(dem.geotransform)
        out.SetProjection(dem.projection)
        for k, plane in enumerate(planes):
            b = out.GetRasterBand(k + 1)
            b.SetNoDataValue(-9999.0)
            if planes.shape[0] > 1:  # a band per direction: which way it looks, as a compass bearing
                b.SetDescription(direction_description(dem.geotransform, k, planes.shape[0]))
            b.WriteArray(np.where(dem.holes, np.float32(-9999.0), plane))
        out.FlushCache()
        failed = gdal.GetLastErrorType() >= gdal.CE_Failure
        out = None
        if failed:
            gdal.Unlink(temporary)
            raise QgsProcessingException(f"{output}: GDAL cannot write it: {gdal.GetLastErrorMsg()}")
        os.replace(temporary, output)
        # The statistics QGIS kept beside an earlier file of that name describe that file, not this one.
        if os.path.isfile(output + ".aux.xml"):
            os.remove(output + ".aux.xml")
        return {"OUTPUT": output}


def direction_description(geotransform, k, count):
    """Band k of `count` per-direction bands: direction k's azimuth is 360 k / count degrees, measured in the
    pixel grid from +x (columns) towards +y (rows) (docs/contract.md); its bearing on the map follows the
    geotransform (a north-up raster's rows run south)."""
    angle = 2 * math.pi * k / count
    east = math.cos(angle) * geotransform[1] + math.sin(angle) * geotransform[2]
    north = math.cos(angle) * geotransform[4] + math.sin(angle) * geotransform[5]
    bearing = round(math.degrees(math.atan2(east, north)), 2) % 360  # -0.001 is 0.00, not 360.00
    return f"direction {k}: bearing {bearing:.2f} degrees (clockwise from grid north)"


class SkyViewFactor(_Bake):
    key, name_text, method, layer, radius_key = "svf", "Sky-view factor", "relief", "svf", "search_radius"
    help_text = "Fraction of the sky hemisphere visible from each texel (relief's svf)."


class PositiveOpenness(_Bake):
    key, name_text, method, layer = "openness_positive", "Positive openness", "relief", "openness_positive"
    radius_key = "search_radius"
    help_text = "Mean zenith angle to the horizon, in degrees (relief's openness_positive)."


class NegativeOpenness(_Bake):
    key, name_text, method, layer = "openness_negative", "Negative openness", "relief", "openness_negative"
    radius_key = "search_radius"
    help_text = "Mean nadir angle to the horizon below, in degrees (relief's openness_negative)."


class Horizons(_Bake):
    key, name_text, method, layer, radius_key = "horizons", "Horizon angles", "relief", "horizon_deg", "search_radius"
    help_text = "The horizon's elevation in degrees in each direction, one band per direction (relief's horizon_deg)."


class AmbientOcclusion(_Bake):
    key, name_text, method, layer = "ao", "Ambient occlusion", "p1", "ao"
    default_directions = 64
    help_text = "Cosine-weighted visible sky from exact horizons (p1's ao)."


class Hbao(_Bake):
    key, name_text, method, layer, radius_key = "hbao", "Ambient obscurance (HBAO)", "hbao", "obscurance", "radius"
    help_text = "Horizon-based ambient obscurance within a radius (hbao's obscurance)."


ALGORITHMS = [SkyViewFactor, PositiveOpenness, NegativeOpenness, Horizons, AmbientOcclusion, Hbao]
