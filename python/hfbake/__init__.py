"""hfbake: ambient occlusion, sky visibility, horizons and lighting baked from height fields.

Arrays in, arrays out::

    import numpy as np, hfbake
    heights = np.load("dem.npy").astype(np.float32)        # (rows, columns), world units
    out = hfbake.relief(heights, texel_size=2.0, layers=["svf", "openness_positive"])
    out["svf"]                                              # (rows, columns) float32

One function per method (p1, p2, nlp, hbao, lsao, farfield, hsao, vo, relief, sun) takes the method's job keys as
keyword arguments, with the same names, defaults and checks as a job file's bake entry, plus the height
keys (texel_size, wrap, height_scale, height_offset, nodata, nodata_value, curvature, refraction) and the
job's lighting keys (environment, lights, bounces, surface). It returns a dict of layers: one channel as
(H, W), per-direction layers (horizon, horizon_distance, horizon_deg) as (K, H, W), colours and vectors as
(H, W, C). It warns (UserWarning) where the command warns about the heights.

A DEM file: read_dem(path) reads it with GDAL, with the checks a job naming it gets, into heights, holes and
the height keys to pass on.

Jobs: validate(job) and bake(job, out=None) take a job file's path or a dict of one and do what
`hfbake validate` and `hfbake bake` do; compare(now, baseline) is `hfbake compare`.

Bad input raises InputError (a ValueError) with the command line's message and the JSON pointer of the
value; a bake stopped by `cancel` raises Cancelled, one stopped by Ctrl-C KeyboardInterrupt.
"""

import inspect as _inspect
import json as _json
import os as _os
import tempfile as _tempfile
import warnings as _warnings

import numpy as _np


class InputError(ValueError):
    """Bad input: a value the caller can fix.

    message: what is wrong (the command line's message); pointer: the JSON pointer of the value
    ("/directions" for a keyword argument, "/bake/0/directions" in a job); file: the job file ("" for
    arrays); lines: every problem found, each as the command line prints it ("<file>: <pointer>: <what>").
    """

    def __init__(self, message, pointer="", file="", lines=None):
        self.message = message
        self.pointer = pointer
        self.file = file
        self.lines = list(lines) if lines is not None else [message]
        super().__init__(self.lines[0] if len(self.lines) == 1 else "\n".join(self.lines))


class Cancelled(RuntimeError):
    """A bake stopped because its `cancel` event was set; nothing it made is kept."""


from . import _hfbake  # noqa: E402  (the exceptions above are what it raises)

__version__ = _hfbake.__version__

_HEIGHT_KEYS = ("texel_size", "wrap", "height_scale", "height_offset", "nodata", "nodata_value", "curvature",
                "refraction")
_JOB_KEYS = ("environment", "lights", "bounces", "surface")


def _method_keys(name):
    schema = _json.loads(_hfbake.method_schema(name) or "{}")
    return [k for k in schema.get("properties", {}) if k != "method"]


def _run_arguments(threads, memory_limit, progress=None, cancel=None):
    """threads and memory_limit as the module takes them (0: all cores), or InputError naming the argument:
    the command line's ranges (--threads 1..4096, a memory limit of at least a byte), a `progress` that can be
    called, a `cancel` with an is_set() that can be called; refused before anything is baked."""
    def integer(x):
        return isinstance(x, (int, _np.integer)) and not isinstance(x, (bool, _np.bool_))

    def kind(x):
        return type(x).__name__
    if threads is not None and not (integer(threads) and 1 <= threads <= 4096):
        raise InputError("must be an integer from 1 to 4096 (or None: all cores)", "/threads")
    if memory_limit is not None and not (integer(memory_limit) and 1 <= memory_limit < 2**63):
        raise InputError("must be a whole number of bytes, at least 1 (or None: the available memory)",
                         "/memory_limit")
    if progress is not None and not callable(progress):
        raise InputError("must be a function called with the fraction done (or None); it is a "
                         f"{kind(progress)}", "/progress")
    if cancel is not None and not callable(getattr(cancel, "is_set", None)):
        raise InputError("must have an is_set() method, as a threading.Event (or be None); it is a "
                         f"{kind(cancel)}", "/cancel")
    return int(threads or 0), None if memory_limit is None else int(memory_limit)


def _wider_than_float(values):
    """Whether an array's values are floats wider than float32 (float64, longdouble)."""
    return _np.issubdtype(values.dtype, _np.floating) and values.dtype.itemsize > 4


def _beyond_float_range(values, nodata_value):
    """(column, row, value) of the first finite value of a float array that a float32 cannot hold, other than
    nodata_value, or None: as a job's Float64 band, such a value is refused, not taken for an infinite hole
    (docs/gis.md)."""
    if not _wider_than_float(values):
        return None
    beyond = _np.isfinite(values) & (_np.abs(values) > _np.finfo(_np.float32).max)
    if isinstance(nodata_value, (int, float, _np.integer, _np.floating)) and not isinstance(nodata_value, bool):
        beyond &= values != nodata_value
    if not beyond.any():
        return None
    row, col = (int(i) for i in _np.argwhere(beyond)[0])
    return col, row, float(values[row, col])


def _beyond_float_range_message(col, row, value, nodata_name):
    return (f"texel ({col}, {row}) is {value:g}, beyond a float's range: heights are baked as floats (if it "
            f"marks missing data, {nodata_name})")


def _as_float_heights(heights, nodata_value):
    """A float64 (or wider) 2-D array as the float32 heights are baked from, its values beyond float's range
    refused (_beyond_float_range) unless they are nodata_value (then infinities: holes). Anything else is
    returned as it is."""
    if not (isinstance(heights, _np.ndarray) and heights.ndim == 2):
        return heights
    beyond = _beyond_float_range(heights, nodata_value)
    if beyond:
        message = "heights: " + _beyond_float_range_message(*beyond, "give it as nodata_value")
        raise InputError(message, "/heights", lines=["/heights: " + message])
    if not _wider_than_float(heights):
        return heights
    with _np.errstate(over="ignore"):
        return heights.astype(_np.float32)


def _bake_array(method, heights, threads, progress, cancel, memory_limit, job_keys, params):
    # A method's own key wins over a job key of the same name (p1's lights, p2's bounces, hbao's surface);
    # `job` gives the job's.
    own = set(_method_keys(method))
    if job_keys is not None and not isinstance(job_keys, dict):
        raise InputError("must be a dict of job keys (environment, lights, bounces, surface) or None; it is a "
                         f"{type(job_keys).__name__}", "/job")
    entry, height, job = {}, {}, dict(job_keys or {})
    if isinstance(heights, _np.ma.MaskedArray):  # its masked texels are holes, as a file's NoData values
        masked = _np.ma.getmaskarray(heights)
        if masked.any() and params.get("nodata") != "fill":
            row, column = (int(v) for v in _np.argwhere(masked)[0])
            raise InputError(f"heights: texel ({column}, {row}) is masked ({int(masked.sum())} of {masked.size} "
                             "texels have no valid height); nodata=\"fill\" fills the holes", "/heights")
        heights = heights.astype(_np.float64).filled(_np.nan)
    heights = _as_float_heights(heights, params.get("nodata_value"))
    for key, value in params.items():
        if value is None:
            continue
        if key == "nodata_value" and isinstance(value, (float, _np.floating)) and _np.isnan(value):
            continue  # a band's NoData of NaN: NaN heights are holes already
        if key in own:
            entry[key] = value
        elif key in _HEIGHT_KEYS:
            height[key] = value
        elif key in _JOB_KEYS:
            job[key] = value
        else:
            entry[key] = value  # refused by the method's schema as the job file would be
    threads, memory_limit = _run_arguments(threads, memory_limit, progress, cancel)
    layers, warnings = _hfbake.bake_array(method, heights, entry, height, job, threads, progress, cancel,
                                          memory_limit)
    for line in warnings:
        _warnings.warn(line, UserWarning, stacklevel=3)  # at the caller of the method's function
    return layers


def _method_doc(name):
    schema = _json.loads(_hfbake.method_schema(name) or "{}")
    lines = [_hfbake.method_summary(name) or schema.get("description", ""), ""]
    lines.append("heights: a 2-D array (rows, columns) of heights in world units; a C-contiguous float32 "
                 "array is taken as it is, others are converted first (the bake holds one copy).")
    lines.append("Returns a dict layer name -> float32 array: (H, W), (K, H, W) per direction, or (H, W, C).")
    lines.append("")
    lines.append("Method keys (absent or None: the job's default):")
    for key, spec in schema.get("properties", {}).items():
        if key == "method":
            continue
        lines.append(f"  {key}: {spec.get('description', '')}")
    lines.append("")
    lines.append("Field and lighting keys: texel_size (default 1), wrap ('clamp' or 'repeat'), height_scale, "
                 "height_offset, nodata ('error' or 'fill'), nodata_value, curvature (default False; world "
                 "units taken as metres), refraction; environment, lights, bounces, "
                 "surface as in a job file. job: a dict of those job keys, for a name the method's own key "
                 "takes (p1's lights, p2's bounces, the obscurance methods' surface).")
    lines.append("threads: worker threads (default: all cores; the bits do not depend on it). progress: called "
                 "with the fraction done (0..1) on the calling thread. cancel: an object with is_set() "
                 "(threading.Event) polled while baking: Cancelled is raised when it is set. memory_limit: "
                 "bytes the memory estimate must fit (default: the available memory).")
    lines.append("Raises InputError (a ValueError) with the command line's message for bad input. Warns "
                 "(UserWarning) where the command warns about the heights: a flat field, a relief implausible "
                 "for the field's extent (16-bit levels taken as world units).")
    return "\n".join(lines)


def _make_method(name):
    keys = _method_keys(name)

    def bake(heights, *, job=None, threads=None, progress=None, cancel=None, memory_limit=None, **params):
        return _bake_array(name, heights, threads, progress, cancel, memory_limit, job, params)

    P = _inspect.Parameter
    parameters = [P("heights", P.POSITIONAL_OR_KEYWORD)]
    for key in keys + [k for k in _HEIGHT_KEYS + _JOB_KEYS if k not in keys]:
        parameters.append(P(key, P.KEYWORD_ONLY, default=None))
    for key in ("job", "threads", "progress", "cancel", "memory_limit"):
        parameters.append(P(key, P.KEYWORD_ONLY, default=None))
    bake.__signature__ = _inspect.Signature(parameters)
    bake.__name__ = bake.__qualname__ = name
    bake.__doc__ = _method_doc(name)
    return bake


methods = tuple(_hfbake.method_names())
for _name in methods:
    globals()[_name] = _make_method(_name)
del _name


def validate(job, *, memory_limit=None):
    """Checks a job (a path to a job file, or a dict of one) as `hfbake validate` does: the schema, every
    method's and the reference's parameters, the memory estimate, the inputs loaded. Returns
    {"name", "width", "height", "memory_bytes", "memory_parts", "heights", "warnings"} ("heights": the line
    `hfbake validate` prints about them, in world units; "warnings": its warnings, one line each, also issued
    through Python's warnings module as UserWarning); raises InputError listing every problem."""
    info = _hfbake.validate(job, _run_arguments(None, memory_limit)[1])
    for line in info["warnings"]:
        _warnings.warn(line, UserWarning, stacklevel=2)
    return info


def bake(job, out=None, *, threads=None, progress=None, cancel=None, memory_limit=None, cache=True,
         overwrite=False):
    """Bakes a job (a path to a job file, or a dict of one; relative paths in a dict resolve against the
    current folder) as `hfbake bake --out OUT` does, writing its outputs into `out` (a folder; None: a
    temporary one, removed afterwards).

    Returns (layers, report): layers[stem][layer] as arrays (the values as baked, before the EXR's pixel
    type), the reference's under "reference"; report: status ("ok" or "regressed" when a threshold failed),
    errors, warnings (what `hfbake bake` warns about, one line each, also issued through Python's warnings
    module as UserWarning), per-method seconds and metrics, the output files, and report.json's content
    under "report" when the job has a reference. `cache`: use the reference cache (~/.cache/hfbake) as the
    command does.
    `overwrite`: as the command's --overwrite, replace outputs of the same job name that another job (file, or
    a dict: every dict job counts as one) baked into `out`."""
    if out is None:
        with _tempfile.TemporaryDirectory(prefix="hfbake-") as tmp:
            layers, report = _bake_job(job, tmp, threads, progress, cancel, memory_limit, cache, overwrite)
            report["outputs"] = []
    else:
        layers, report = _bake_job(job, _os.fspath(out), threads, progress, cancel, memory_limit, cache,
                                   overwrite)
    for line in report["warnings"]:
        _warnings.warn(line, UserWarning, stacklevel=2)
    return layers, report


def _bake_job(job, out, threads, progress, cancel, memory_limit, cache, overwrite):
    threads, memory_limit = _run_arguments(threads, memory_limit, progress, cancel)
    for name, value in (("cache", cache), ("overwrite", overwrite)):
        if not isinstance(value, (bool, _np.bool_)):
            raise InputError(f"must be True or False; it is a {type(value).__name__}", "/" + name)
    layers, summary = _hfbake.bake_job(job, out, threads, progress, cancel, memory_limit, cache, overwrite)
    report = _json.loads(summary)
    for path in report["outputs"]:
        if _os.path.basename(path) == "report.json":
            with open(path) as f:
                report["report"] = _json.load(f)
    return layers, report


def compare(now, baseline, *, tolerances=(), allow_different_job=False, update_baseline=False):
    """Compares a bake's report.json (or every report.json under a folder) with a baseline, as
    `hfbake compare NOW BASELINE` does (`tolerances`: "METRIC=REL[,ABS]" strings, as --tolerance).

    Returns {"regression": bool, "comparisons": [...] (what --json writes), "text": the command's tables,
    "baseline_updated": bool}. Raises InputError for bad input and for a baseline of another job (unless
    allow_different_job)."""
    if isinstance(tolerances, str):  # one tolerance, not its characters
        tolerances = [tolerances]
    result = _hfbake.compare(_os.fspath(now), _os.fspath(baseline), list(tolerances), allow_different_job,
                             update_baseline)
    return _json.loads(result)


def height_unit_factor(height_unit, pixel_metres=1.0):
    """The factor that converts heights in `height_unit` (a raster band's unit type as GDAL gives it: "m",
    "ft", "US survey foot", ...) into the unit of pixels `pixel_metres` metres long (a projected CRS's
    GetLinearUnits(); 1 for metres). None when the unit is empty or not one of the metre (and its mm, cm, dm
    and km), the international foot and the US survey foot. InputError for a unit that is not a str or a
    pixel_metres that is not a positive number. The heights an array function takes are in the pixels'
    unit (texel_size's)."""
    if height_unit is not None and not isinstance(height_unit, str):
        raise InputError(f"must be a unit's name (a str) or None; it is a {type(height_unit).__name__}",
                         "/height_unit")
    if isinstance(pixel_metres, bool) or not isinstance(pixel_metres, (int, float, _np.number)) or \
            not (_np.isfinite(pixel_metres) and pixel_metres > 0):
        raise InputError(f"must be a positive number of metres; it is {pixel_metres!r}", "/pixel_metres")
    metres = _hfbake.metres_per((height_unit or "").strip())
    return None if metres is None else metres / pixel_metres


class Dem:
    """A DEM as the array functions take it (read_dem): `heights` (float32, rows x columns, in the pixels'
    unit), `holes` (bool: NoData, NaN or infinite), `keys` (the height keys for the array functions:
    texel_size, and nodata="fill" with the band's nodata_value when it has holes), `geotransform` and
    `projection` (GDAL's, for writing results back), `warnings` (one line each, as `hfbake validate` says
    them: heights converted into the pixels' unit, a CRS far from true scale)."""

    def __init__(self, heights, holes, keys, geotransform, projection, warnings):
        self.heights, self.holes, self.keys = heights, holes, keys
        self.geotransform, self.projection, self.warnings = geotransform, projection, warnings


def read_dem(path, band=1, unscale=False):
    """Reads band `band` of the raster at `path` with GDAL (Debian's python3-gdal) for the array functions,
    with the checks a job naming the file gets: a CRS that is projected (a geographic DEM's pixels are
    degrees: warp it, or bake a job naming the file, docs/gis.md), square unrotated pixels (sides equal to
    1e-9), heights converted into the pixels' unit (height_unit_factor), NoData, NaN and infinite heights as
    holes (filled for the bake: write results back as NoData there; a PNG's NoData, its tRNS colour, is a
    height, as a job reads it), and a warning where the CRS's map units are not ground units (Web Mercator
    away from the equator flattens every slope). The heights are the stored values, as a job's are, unless
    `unscale` is true: then stored x scale + offset as the band declares them (GDAL's scale and offset, as
    QGIS shows the band). Raises InputError naming the file."""
    from osgeo import gdal  # noqa: PLC0415  (only this function needs GDAL)

    path = _os.fspath(path)

    def refuse(message):
        raise InputError(message, "/height/image", path, [f"{path}: {message}"])

    if isinstance(band, (bool, _np.bool_)) or not isinstance(band, (int, _np.integer)):
        raise InputError(f"must be a band number (an int from 1); it is {band!r}", "/band", path)
    if not isinstance(unscale, (bool, _np.bool_)):
        raise InputError(f"must be True or False; it is {unscale!r}", "/unscale", path)
    if _os.path.isdir(path):
        refuse("is a folder, not a raster file")
    if not _os.path.isfile(path):
        refuse("no such file")
    used = gdal.GetUseExceptions()
    gdal.DontUseExceptions()
    try:
        dem = gdal.Open(path)
        if dem is None:
            refuse(f"GDAL cannot read it as a raster ({gdal.GetLastErrorMsg().strip()})")
    finally:
        if used:
            gdal.UseExceptions()
    if not 1 <= band <= dem.RasterCount:
        refuse(f"has no band {band} (bands are numbered from 1; it has {dem.RasterCount})")
    gt = dem.GetGeoTransform(can_return_null=True)
    if gt is None and dem.GetGCPCount() > 0:
        refuse("is placed by ground control points, not by a geotransform: warp it onto a north-up grid first "
               f"(gdalwarp {path} warped.tif)")
    crs = dem.GetSpatialRef()
    if crs is None:
        refuse("has no CRS: the texel size would be a guess (assign its projected CRS first)")
    if gt is None:
        refuse(f"has a CRS ({crs.GetName()}) but no geotransform, so its pixels have no size or place in it: "
               "give it one (gdal_edit.py -a_ullr)")
    if crs.IsGeographic():
        refuse("its pixels are degrees of a geographic CRS: warp it to a projected CRS first, or bake a job "
               "naming the file, which reads a lon/lat DEM's texel sizes itself (docs/gis.md)")
    sx, sy = abs(gt[1]), abs(gt[5])
    if not (abs(gt[2]) <= 1e-9 * sx and abs(gt[4]) <= 1e-9 * sy):  # north_up, as a job reading the file
        refuse("has rotated pixels: warp it north-up first (gdalwarp)")
    if not abs(sx - sy) <= 1e-9 * max(sx, sy):
        refuse(f"has non-square pixels ({sx!r} x {sy!r}); hfbake needs square texels: resample it first, e.g. "
               "gdalwarp -tr S S")
    gap = _hfbake.uncovered_problem(path, band - 1)
    if gap:
        refuse(gap)
    b = dem.GetRasterBand(band)
    values = b.ReadAsArray()
    # A PNG's NoData (GDAL reports its tRNS colour so) is a height, and it has no mask of its heights, as a
    # job reads it (docs/heights.md).
    png = dem.GetDriver().ShortName == "PNG"
    # GDAL's mask band (a .msk side file or an internal mask; not an alpha band, nor the NoData value again):
    # its invalid texels are holes, as a job reading the file makes them.
    flags = b.GetMaskFlags()
    if not png and not flags & (gdal.GMF_ALL_VALID | gdal.GMF_NODATA | gdal.GMF_ALPHA):
        values = _np.where(b.GetMaskBand().ReadAsArray() == 0, _np.nan, values.astype(_np.float64))
    # North up and east right, as the array functions take it (their north is row 0, their east the last
    # column): a south-up or east-west raster is turned, and its geotransform with it.
    gt = tuple(gt)
    if gt[5] > 0:
        values = values[::-1, :]
        gt = (gt[0], gt[1], 0.0, gt[3] + gt[5] * dem.RasterYSize, 0.0, -gt[5])
    if gt[1] < 0:
        values = values[:, ::-1]
        gt = (gt[0] + gt[1] * dem.RasterXSize, -gt[1], 0.0, gt[3], 0.0, gt[5])
    values = _np.ascontiguousarray(values)
    nodata = None if png else b.GetNoDataValue()
    beyond = _beyond_float_range(values, nodata)
    if beyond:
        refuse(_beyond_float_range_message(*beyond, "declare it the band's NoData value"))
    # A texel is a hole where its height, as the float a job bakes, equals the NoData value as a float: a
    # Float32 band declaring -9999.9 stores the float nearest it (a job reading the file compares so too).
    holes = ~_np.isfinite(values.astype(_np.float64))
    if nodata is not None and _np.isfinite(nodata):
        with _np.errstate(over="ignore"):
            holes |= values.astype(_np.float32) == _np.float32(nodata)
    values = values.astype(_np.float64)
    warnings = []
    scale_of, offset_of = b.GetScale(), b.GetOffset()
    scale_of = 1.0 if scale_of is None else scale_of
    offset_of = 0.0 if offset_of is None else offset_of
    declared = scale_of != 1.0 or offset_of != 0.0
    if declared and unscale:
        values = values * scale_of + offset_of
        if not _np.isfinite(values[~holes]).all():
            refuse(f"its declared scale {scale_of:g} and offset {offset_of:g} take heights beyond a float's range")
        warnings.append(f"{path}: the file declares scale {scale_of:g} and offset {offset_of:g}: heights are "
                        f"stored x {scale_of:g} + {offset_of:g} (unscale=True)")
    elif declared:
        warnings.append(f"{path}: the file declares scale {scale_of:g} and offset {offset_of:g}, not applied "
                        "(heights are the stored values): unscale=True, or height_scale and height_offset, "
                        "apply them")
    heights = _np.where(holes, _np.nan, values).astype(_np.float32)
    linear = crs.GetLinearUnits() if crs.IsProjected() else 1.0
    factor = height_unit_factor(b.GetUnitType(), linear)
    if factor is not None and abs(factor - 1) > 1e-4:
        heights[~holes] *= _np.float32(factor)
        warnings.append(f"{path}: the band's heights are in {b.GetUnitType()}, its pixels in "
                        f"{crs.GetLinearUnitsName()}: heights x {factor:.6g} into the pixels' unit")
    if crs.IsProjected():
        note = _hfbake.unitless_heights_note(crs.GetLinearUnitsName() or "", linear, b.GetUnitType() or "")
        if note:
            warnings.append(f"{path}: {note}")
    centre_x = gt[0] + gt[1] * dem.RasterXSize / 2
    centre_y = gt[3] + gt[5] * dem.RasterYSize / 2
    scale = _hfbake.site_scale_warning(crs.ExportToWkt(), centre_x, centre_y, crs.GetName() or "")
    if scale:
        warnings.append(f"{path}: {scale}")
    keys = {"texel_size": sx}
    if holes.any():
        keys["nodata"] = "fill"
    return Dem(heights, holes, keys, gt, dem.GetProjection(), warnings)
