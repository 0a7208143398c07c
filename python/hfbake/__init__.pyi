"""Type stubs of hfbake (see the package's docstring and help(hfbake.<method>))."""
import os
import threading
from typing import Any, Callable, Mapping, Optional, Sequence, Union

import numpy as np
import numpy.typing as npt

__version__: str
methods: tuple[str, ...]

class InputError(ValueError):
    message: str
    pointer: str
    file: str
    lines: list[str]
    def __init__(self, message: str, pointer: str = ..., file: str = ..., lines: Optional[Sequence[str]] = ...) -> None: ...

class Cancelled(RuntimeError): ...

Heights = npt.ArrayLike
Layers = dict[str, npt.NDArray[np.float32]]
Job = Union[str, os.PathLike, Mapping[str, Any]]

def p1(
    heights: Heights,
    *,
    texel_size: Optional[float] = ...,
    wrap: Optional[str] = ...,
    height_scale: Optional[float] = ...,
    height_offset: Optional[float] = ...,
    nodata: Optional[str] = ...,
    nodata_value: Optional[float] = ...,
    environment: Optional[Mapping[str, Any]] = ...,
    lights: Optional[Sequence[Mapping[str, Any]]] = ...,
    bounces: Optional[int] = ...,
    surface: Optional[Mapping[str, Any]] = ...,
    layers: Optional[Sequence[str]] = ...,
    job: Optional[Mapping[str, Any]] = ...,
    threads: Optional[int] = ...,
    progress: Optional[Callable[[float], None]] = ...,
    cancel: Optional[threading.Event] = ...,
    memory_limit: Optional[int] = ...,
    **params: Any,
) -> Layers: ...

def p2(
    heights: Heights,
    *,
    texel_size: Optional[float] = ...,
    wrap: Optional[str] = ...,
    height_scale: Optional[float] = ...,
    height_offset: Optional[float] = ...,
    nodata: Optional[str] = ...,
    nodata_value: Optional[float] = ...,
    environment: Optional[Mapping[str, Any]] = ...,
    lights: Optional[Sequence[Mapping[str, Any]]] = ...,
    bounces: Optional[int] = ...,
    surface: Optional[Mapping[str, Any]] = ...,
    layers: Optional[Sequence[str]] = ...,
    job: Optional[Mapping[str, Any]] = ...,
    threads: Optional[int] = ...,
    progress: Optional[Callable[[float], None]] = ...,
    cancel: Optional[threading.Event] = ...,
    memory_limit: Optional[int] = ...,
    **params: Any,
) -> Layers: ...

def nlp(
    heights: Heights,
    *,
    texel_size: Optional[float] = ...,
    wrap: Optional[str] = ...,
    height_scale: Optional[float] = ...,
    height_offset: Optional[float] = ...,
    nodata: Optional[str] = ...,
    nodata_value: Optional[float] = ...,
    environment: Optional[Mapping[str, Any]] = ...,
    lights: Optional[Sequence[Mapping[str, Any]]] = ...,
    bounces: Optional[int] = ...,
    surface: Optional[Mapping[str, Any]] = ...,
    layers: Optional[Sequence[str]] = ...,
    job: Optional[Mapping[str, Any]] = ...,
    threads: Optional[int] = ...,
    progress: Optional[Callable[[float], None]] = ...,
    cancel: Optional[threading.Event] = ...,
    memory_limit: Optional[int] = ...,
    **params: Any,
) -> Layers: ...

def hbao(
    heights: Heights,
    *,
    texel_size: Optional[float] = ...,
    wrap: Optional[str] = ...,
    height_scale: Optional[float] = ...,
    height_offset: Optional[float] = ...,
    nodata: Optional[str] = ...,
    nodata_value: Optional[float] = ...,
    environment: Optional[Mapping[str, Any]] = ...,
    lights: Optional[Sequence[Mapping[str, Any]]] = ...,
    bounces: Optional[int] = ...,
    surface: Optional[Mapping[str, Any]] = ...,
    layers: Optional[Sequence[str]] = ...,
    job: Optional[Mapping[str, Any]] = ...,
    threads: Optional[int] = ...,
    progress: Optional[Callable[[float], None]] = ...,
    cancel: Optional[threading.Event] = ...,
    memory_limit: Optional[int] = ...,
    **params: Any,
) -> Layers: ...

def lsao(
    heights: Heights,
    *,
    texel_size: Optional[float] = ...,
    wrap: Optional[str] = ...,
    height_scale: Optional[float] = ...,
    height_offset: Optional[float] = ...,
    nodata: Optional[str] = ...,
    nodata_value: Optional[float] = ...,
    environment: Optional[Mapping[str, Any]] = ...,
    lights: Optional[Sequence[Mapping[str, Any]]] = ...,
    bounces: Optional[int] = ...,
    surface: Optional[Mapping[str, Any]] = ...,
    layers: Optional[Sequence[str]] = ...,
    job: Optional[Mapping[str, Any]] = ...,
    threads: Optional[int] = ...,
    progress: Optional[Callable[[float], None]] = ...,
    cancel: Optional[threading.Event] = ...,
    memory_limit: Optional[int] = ...,
    **params: Any,
) -> Layers: ...

def farfield(
    heights: Heights,
    *,
    texel_size: Optional[float] = ...,
    wrap: Optional[str] = ...,
    height_scale: Optional[float] = ...,
    height_offset: Optional[float] = ...,
    nodata: Optional[str] = ...,
    nodata_value: Optional[float] = ...,
    environment: Optional[Mapping[str, Any]] = ...,
    lights: Optional[Sequence[Mapping[str, Any]]] = ...,
    bounces: Optional[int] = ...,
    surface: Optional[Mapping[str, Any]] = ...,
    layers: Optional[Sequence[str]] = ...,
    job: Optional[Mapping[str, Any]] = ...,
    threads: Optional[int] = ...,
    progress: Optional[Callable[[float], None]] = ...,
    cancel: Optional[threading.Event] = ...,
    memory_limit: Optional[int] = ...,
    **params: Any,
) -> Layers: ...

def hsao(
    heights: Heights,
    *,
    texel_size: Optional[float] = ...,
    wrap: Optional[str] = ...,
    height_scale: Optional[float] = ...,
    height_offset: Optional[float] = ...,
    nodata: Optional[str] = ...,
    nodata_value: Optional[float] = ...,
    environment: Optional[Mapping[str, Any]] = ...,
    lights: Optional[Sequence[Mapping[str, Any]]] = ...,
    bounces: Optional[int] = ...,
    surface: Optional[Mapping[str, Any]] = ...,
    layers: Optional[Sequence[str]] = ...,
    job: Optional[Mapping[str, Any]] = ...,
    threads: Optional[int] = ...,
    progress: Optional[Callable[[float], None]] = ...,
    cancel: Optional[threading.Event] = ...,
    memory_limit: Optional[int] = ...,
    **params: Any,
) -> Layers: ...

def vo(
    heights: Heights,
    *,
    texel_size: Optional[float] = ...,
    wrap: Optional[str] = ...,
    height_scale: Optional[float] = ...,
    height_offset: Optional[float] = ...,
    nodata: Optional[str] = ...,
    nodata_value: Optional[float] = ...,
    environment: Optional[Mapping[str, Any]] = ...,
    lights: Optional[Sequence[Mapping[str, Any]]] = ...,
    bounces: Optional[int] = ...,
    surface: Optional[Mapping[str, Any]] = ...,
    layers: Optional[Sequence[str]] = ...,
    job: Optional[Mapping[str, Any]] = ...,
    threads: Optional[int] = ...,
    progress: Optional[Callable[[float], None]] = ...,
    cancel: Optional[threading.Event] = ...,
    memory_limit: Optional[int] = ...,
    **params: Any,
) -> Layers: ...

def relief(
    heights: Heights,
    *,
    texel_size: Optional[float] = ...,
    wrap: Optional[str] = ...,
    height_scale: Optional[float] = ...,
    height_offset: Optional[float] = ...,
    nodata: Optional[str] = ...,
    nodata_value: Optional[float] = ...,
    environment: Optional[Mapping[str, Any]] = ...,
    lights: Optional[Sequence[Mapping[str, Any]]] = ...,
    bounces: Optional[int] = ...,
    surface: Optional[Mapping[str, Any]] = ...,
    layers: Optional[Sequence[str]] = ...,
    job: Optional[Mapping[str, Any]] = ...,
    threads: Optional[int] = ...,
    progress: Optional[Callable[[float], None]] = ...,
    cancel: Optional[threading.Event] = ...,
    memory_limit: Optional[int] = ...,
    **params: Any,
) -> Layers: ...

def sun(
    heights: Heights,
    *,
    texel_size: Optional[float] = ...,
    wrap: Optional[str] = ...,
    height_scale: Optional[float] = ...,
    height_offset: Optional[float] = ...,
    nodata: Optional[str] = ...,
    nodata_value: Optional[float] = ...,
    environment: Optional[Mapping[str, Any]] = ...,
    lights: Optional[Sequence[Mapping[str, Any]]] = ...,
    bounces: Optional[int] = ...,
    surface: Optional[Mapping[str, Any]] = ...,
    layers: Optional[Sequence[str]] = ...,
    job: Optional[Mapping[str, Any]] = ...,
    threads: Optional[int] = ...,
    progress: Optional[Callable[[float], None]] = ...,
    cancel: Optional[threading.Event] = ...,
    memory_limit: Optional[int] = ...,
    **params: Any,
) -> Layers: ...

def validate(job: Job, *, memory_limit: Optional[int] = ...) -> dict[str, Any]: ...
def bake(
    job: Job,
    out: Union[str, os.PathLike, None] = ...,
    *,
    threads: Optional[int] = ...,
    progress: Optional[Callable[[float], None]] = ...,
    cancel: Optional[threading.Event] = ...,
    memory_limit: Optional[int] = ...,
    cache: bool = ...,
    overwrite: bool = ...,
) -> tuple[dict[str, Layers], dict[str, Any]]: ...
def compare(
    now: Union[str, os.PathLike],
    baseline: Union[str, os.PathLike],
    *,
    tolerances: Sequence[str] = ...,
    allow_different_job: bool = ...,
    update_baseline: bool = ...,
) -> dict[str, Any]: ...
def height_unit_factor(height_unit: Optional[str], pixel_metres: float = ...) -> Optional[float]: ...

class Dem:
    heights: np.ndarray
    holes: np.ndarray
    keys: dict[str, Any]
    geotransform: tuple[float, float, float, float, float, float]
    projection: str
    warnings: list[str]

def read_dem(path: Union[str, os.PathLike[str]], band: int = ..., unscale: bool = ...) -> Dem: ...
