"""Touch on the floor acts as a click does (issue 41, item 5).
The script runs in the page; the server sends it as a page connects, on viser's event loop.

viser's client sends a click on the scene (``ScenePointerMessage``) for a
mouse's press and release, never for a finger's: in Chromium, with real
touch events (``Input.dispatchTouchEvent``) as with emulated taps, a tap on
the floor reached the page as pointer events of type "touch" and the server
heard nothing, while a mouse click at the same place moved the lamp. On a
phone, *Be the light*, the inspector's click on a robot and drawing by
clicks did nothing.

:data:`TOUCH_JS` (``page/touch.js``), sent to each page at connect (:mod:`sandbox.app.web.gate`),
turns a finger into the mouse viser listens to, on the scene's canvas only:

- **A tap** (one finger, down and up within :data:`TAP_PX` and
  :data:`TAP_MS`) becomes a mouse press and release at the same point,
  which viser sends as its click. A finger that moves is viser's camera's
  (pan, pinch), as before.
- **While the lamp is lit** (the panel shows *Give the light back*), one
  finger is the lamp's: its events stop before viser's camera hears them,
  and the finger's path becomes clicks, one every :data:`DRAG_PX` pixels
  (viser sends at most one click per 20 ms), so a drag leads the lamp, or
  paints lights with the brush. The view does not move by touch meanwhile
  (a second finger is left to viser's camera, which never heard the
  first): *Give the light back* frees it.

The server decides as for a mouse click: what a click does, and whether this
page may do it (a watching page's clicks are refused).

:data:`CLIENT` is what the script relies on in viser's client, checked against the installed viser's
bundle (:mod:`sandbox.app.web.client_seam`).
"""

from __future__ import annotations

from sandbox.app.web.client_seam import Relies, script

#: The most a tap may move (px) and last (ms); beyond, the finger moves the camera.
TAP_PX = 10
TAP_MS = 600
#: A dragged lamp is moved every this many pixels of the finger's path.
DRAG_PX = 16
#: The label the lamp's button carries while the lamp is lit (sandbox.app.panel.lamp).
LAMP_LIT_LABEL = "Give the light back"
#: The id our mouse events carry (a finger's ids are small numbers; the mouse's is 1).
MOUSE_ID = 7041

TOUCH_JS = script("touch.js", tap_px=TAP_PX, tap_ms=TAP_MS, drag_px=DRAG_PX, lit=LAMP_LIT_LABEL,
                  mouse_id=MOUSE_ID)

# viser's canvas: a press there starts a gesture (none while one is under way), and a release without a move
# sends the click.
_CANVAS_HEARS = r"onPointerDown:[\w$]+,onPointerMove:[\w$]+,onPointerUp:[\w$]+,onPointerCancel:"
_CLICK_SENT = r"type:`ScenePointerMessage`,event_type:`click`"
_ONE_GESTURE = r"onPointerDown\([\w$]+\)\{if\(this\.gesture\.kind!==`idle`"

#: What touch.js relies on in viser's client (sandbox.app.web.client_seam).
CLIENT = (
    Relies("canvas", "viser draws the scene on a canvas that fills the viewer (React Three Fiber's): the "
           "largest of the page's canvases, its charts' are smaller", found=(r"\(`canvas`,\{ref:[\w$]+,style:",)),
    Relies("button", "viser's buttons are Mantine's (an UnstyledButton, a <button>) with their label as their "
           "text: the lamp's button says whether the lamp is lit",
           found=(r"\.displayName=`@mantine/core/Button`", r"component:[\w$]+=`button`")),
    Relies("pointerdown", "viser's canvas hears a press (it starts a gesture, unless one is under way: the "
           "script's click waits for the finger's gesture to end)", found=(_CANVAS_HEARS, _ONE_GESTURE)),
    Relies("pointerup", "... and a release: one without a move sends the click (ScenePointerMessage)",
           found=(_CANVAS_HEARS, _CLICK_SENT)),
    Relies("mouse", "viser's camera (camera-controls) takes a mouse's press by its buttons and a finger's as a "
           "touch (pan, pinch): the script's click is a mouse's",
           found=(r"pointerType===`mouse`\?", r"pointerType===`touch`\)switch")),
)
