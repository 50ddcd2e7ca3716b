"""The messages a page may send, decoded and checked in one pass: :func:`decode`.
Pure functions, called on viser's event loop.

viser decodes whatever a page sends into the message class its ``type`` names, converting each field
as its annotation says (``float(value)``, ``int(value)``), and raises on anything else: a field that
is not the class's, a missing one, a string where a number goes, an unknown ``type``. Raised in the
loop that reads a connection, that closed the page's connection with a traceback (issue 54, G); a
camera whose ``image_height`` was 0 passed, and the page's camera then divided by it (F).

Here each kind a page's script can send (:data:`PAGE_KINDS`, read from viser's client) is a msgspec
structure generated from the viser class's own annotations, with bounds: every number finite and
within :data:`LARGEST`, every list of any length at most :data:`MOST_ITEMS` long, a camera's sizes
positive and bounded (:data:`CAMERA_BOUNDS`). msgspec decodes and checks in one pass, in C, and stops
at the first field that is wrong; its one line says where (``Expected `int` >= 1 - at
`$.image_height```). A message larger than :data:`LARGE_MESSAGE` may only be an upload's part (the
only large thing a page sends: the app never asks a page for a render), decoded as one, so a megabyte of nested lists is refused at its first
byte out of place rather than built. What passes becomes viser's own message object, as viser's
decoder would have built it.
"""

from __future__ import annotations

import dataclasses
import math
import typing
from typing import Annotated, Any, Union

import msgspec

from sandbox.app.web.viser_seam import messages

#: Every kind of message viser's client sends (its ``sendMessage`` calls, viser 1.1.1). The inbox
#: then decides which of them a page may send (sandbox.app.web.inbox).
PAGE_KINDS = ("ViewerCameraMessage", "GuiUpdateMessage", "GuiButtonHoldMessage", "CommandTriggerMessage",
              "ScenePointerMessage", "SceneNodeClickMessage", "SceneNodeDragMessage",
              "TransformControlsUpdateMessage", "TransformControlsDragStartMessage",
              "TransformControlsDragEndMessage", "FileTransferStartUpload", "FileTransferPart",
              "GuiFormSubmitMessage", "GuiFormDirtyMessage", "GetRenderResponseMessage",
              "LocalStorageGetItemResponseMessage", "ShareUrlRequest", "ShareUrlDisconnect")
#: Largest magnitude of any number in a message (a camera a thousand kilometres away is still inside).
LARGEST = 1e9
#: Longest list of any length (a rectangle selection sends 2 points, a GUI update 1 value).
MOST_ITEMS = 16
#: Bytes above which a message can only be an upload's part (viser's client sends 512 KiB parts; a
#: text field's 4,096 characters are at most 16 KiB).
LARGE_MESSAGE = 64 * 1024
#: A page's camera, as viser's client reports it: its canvas in pixels, its field of view (radians),
#: its clipping planes (a canvas of 65,536 pixels is past any screen).
CAMERA_BOUNDS = {"image_height": msgspec.Meta(ge=1, le=65_536), "image_width": msgspec.Meta(ge=1, le=65_536),
                 "fov": msgspec.Meta(gt=0.0, lt=math.pi), "near": msgspec.Meta(gt=0.0, le=LARGEST),
                 "far": msgspec.Meta(gt=0.0, le=LARGEST)}


class Malformed(ValueError):
    """A message no page of ours sends: its one line says what is wrong with it."""


def decode(raw: Any) -> Any:
    """The viser message ``raw`` (a websocket message's bytes) holds, or :class:`Malformed`."""
    if not isinstance(raw, bytes):
        raise Malformed("a text frame (viser's messages are binary)")
    decoder = _PART_DECODER if len(raw) > LARGE_MESSAGE else _DECODER
    try:
        decoded = decoder.decode(raw)
    except msgspec.ValidationError as why:
        if len(raw) > LARGE_MESSAGE:
            raise Malformed(f"a message of {len(raw)} bytes that is not an upload's part ({why})") from None
        raise Malformed(str(why)) from None
    except msgspec.DecodeError as why:
        raise Malformed(str(why)) from None
    kind = type(decoded).__name__
    if kind == "ViewerCameraMessage":
        _check_camera(decoded)
    try:
        return _VISER_CLASS[kind](**msgspec.structs.asdict(decoded))
    except (TypeError, ValueError) as why:  # (a viser class that checks more than its annotations say)
        raise Malformed(f"{kind}: {why}") from None


def _check_camera(camera: Any) -> None:
    """What bounds cannot say: an orientation (a unit quaternion), a far plane beyond the near one, an up
    direction."""
    if not 0.5 < math.hypot(*camera.wxyz) < 2.0:
        raise Malformed(f"the camera's orientation {camera.wxyz} is not a unit quaternion")
    if camera.far <= camera.near:
        raise Malformed(f"the camera's far plane {camera.far} is not beyond its near plane {camera.near}")
    if math.hypot(*camera.up_direction) == 0.0:
        raise Malformed("the camera's up direction is zero")


# ------------------------------------------------------------------ structures
_NUMBER_BOUNDS = {float: msgspec.Meta(ge=-LARGEST, le=LARGEST), int: msgspec.Meta(ge=-2 ** 53, le=2 ** 53)}


def _bounded(annotation: Any, bound: msgspec.Meta | None = None) -> Any:
    """``annotation`` (a viser message field's) as msgspec checks it, with this module's bounds."""
    origin, args = typing.get_origin(annotation), typing.get_args(annotation)
    if annotation in _NUMBER_BOUNDS:
        return Annotated[annotation, bound or _NUMBER_BOUNDS[annotation]]
    if origin is tuple:
        if len(args) == 2 and args[1] is Ellipsis:
            return Annotated[tuple[_bounded(args[0]), ...], msgspec.Meta(max_length=MOST_ITEMS)]
        return tuple[tuple(_bounded(arg) for arg in args)]
    if origin is Union:
        return Union[tuple(_bounded(arg) for arg in args)]
    if origin is dict:
        return Annotated[dict[_bounded(args[0]), Any], msgspec.Meta(max_length=MOST_ITEMS)]
    return annotation  # str, bytes, Literal[...], Any


def _structure(viser_class: type) -> type:
    """A msgspec structure with ``viser_class``'s fields (tagged by its name in ``type``, as viser's
    client sends it), no others."""
    hints = typing.get_type_hints(viser_class)
    bounds = CAMERA_BOUNDS if viser_class.__name__ == "ViewerCameraMessage" else {}
    fields = [(field.name, _bounded(hints[field.name], bounds.get(field.name)))
              + (() if field.default is dataclasses.MISSING else (field.default,))
              for field in dataclasses.fields(viser_class) if field.name in hints]
    fields.sort(key=len)  # (msgspec takes the fields with a default last)
    return msgspec.defstruct(viser_class.__name__, fields, tag_field="type", tag=viser_class.__name__,
                             forbid_unknown_fields=True)


#: (A viser that lacks one has none here: sandbox.app.web.viser_seam.check refuses to serve on it.)
_VISER_CLASS = {name: getattr(messages, name) for name in PAGE_KINDS
                if dataclasses.is_dataclass(getattr(messages, name))}
_STRUCTURES = {name: _structure(viser_class) for name, viser_class in _VISER_CLASS.items()}
_DECODER = msgspec.msgpack.Decoder(Union[tuple(_STRUCTURES.values())])
_PART_DECODER = msgspec.msgpack.Decoder(_STRUCTURES["FileTransferPart"])
