"""The box trackers' occlusion models, chosen by name.

Adding a model is adding an entry here: the filter only calls `terms(ctx)`.
"""

from __future__ import annotations

from collections.abc import Callable

from occtrack.occlusion.base import NoOcclusion, OcclusionModel
from occtrack.occlusion.box_geometry import BoxOcclusionGeometry
from occtrack.occlusion.box_measurementwise import MeasurementWise
from occtrack.occlusion.box_objectwise import ObjectWiseExpectedValue

BOX_OCCLUSION_MODELS: dict[str, Callable[..., OcclusionModel]] = {
    "none": lambda geometry, min_existence: NoOcclusion(),
    "object-wise": lambda geometry, min_existence: ObjectWiseExpectedValue(geometry,
                                                                           min_existence),
    "measurement-wise": lambda geometry, min_existence: MeasurementWise(geometry),
}


def box_occlusion(name: str, geometry: BoxOcclusionGeometry | None = None,
                  min_existence: float = 0.1) -> OcclusionModel:
    """The occlusion model called `name` (one of BOX_OCCLUSION_MODELS)."""
    try:
        make = BOX_OCCLUSION_MODELS[name]
    except KeyError:
        raise ValueError(f"unknown occlusion model {name!r}; choose from "
                         f"{', '.join(BOX_OCCLUSION_MODELS)}") from None
    return make(geometry or BoxOcclusionGeometry(), min_existence)
