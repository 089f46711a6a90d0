"""The checks Submit makes before a job is stored, with yarfd's limits."""

from __future__ import annotations

from yarf.v1 import render_pb2

MAX_SPP = 1 << 20
MAX_FILM_SIDE = 16384
MAX_FILM_PIXELS = 1 << 26
MAX_RETRIES = 10


class InvalidRequest(ValueError):
    """A SubmitRequest the farm refuses (INVALID_ARGUMENT), naming the offending part."""


def check_submit(request: render_pb2.SubmitRequest) -> None:
    """Raises InvalidRequest for what no node could render; the nodes' yarfd checks the rest."""
    if not request.HasField("scene"):
        raise InvalidRequest("the request has no scene")
    film = request.scene.film
    if not (1 <= film.width <= MAX_FILM_SIDE and 1 <= film.height <= MAX_FILM_SIDE):
        raise InvalidRequest(
            f"scene.film: {film.width}x{film.height} is not 1 to {MAX_FILM_SIDE} pixels a side"
        )
    if film.width * film.height > MAX_FILM_PIXELS:
        raise InvalidRequest(f"scene.film: {film.width}x{film.height} is over 2^26 pixels")
    options = request.options
    if options.spp > MAX_SPP:
        raise InvalidRequest(f"options.spp: {options.spp} is over {MAX_SPP}")
    spp = options.spp or 16
    if options.first_sample >= spp:
        raise InvalidRequest(f"options.first_sample {options.first_sample} must be below spp {spp}")
    if options.HasField("crop"):
        c = options.crop
        if not (c.x0 < c.x1 <= film.width and c.y0 < c.y1 <= film.height):
            raise InvalidRequest(
                f"options.crop [{c.x0}, {c.x1}) x [{c.y0}, {c.y1}) is not a window of the "
                f"{film.width}x{film.height} film"
            )
    if request.priority > 100:
        raise InvalidRequest(f"priority {request.priority} is not 1 to 100")
    if request.max_retries > MAX_RETRIES:
        raise InvalidRequest(f"max_retries {request.max_retries} is over {MAX_RETRIES}")
