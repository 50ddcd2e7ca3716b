"""Touch on the floor acts as a click does (issue 41, item 5).

viser's client sends a click on the scene (``ScenePointerMessage``) for a
mouse's press and release, never for a finger's: in Chromium, with real
touch events (``Input.dispatchTouchEvent``) as with emulated taps, a tap on
the floor reached the page as pointer events of type "touch" and the server
heard nothing, while a mouse click at the same place moved the lamp. On a
phone, *Be the light*, the inspector's click on a robot and drawing by
clicks did nothing.

:data:`TOUCH_JS`, sent to each page at connect (:mod:`sandbox.app.web.gate`),
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
"""

from __future__ import annotations

import json

#: The most a tap may move (px) and last (ms); beyond, the finger moves the camera.
TAP_PX = 10
TAP_MS = 600
#: A dragged lamp is moved every this many pixels of the finger's path.
DRAG_PX = 16
#: The label the lamp's button carries while the lamp is lit (sandbox.app.panel.lamp).
LAMP_LIT_LABEL = "Give the light back"
#: The id our mouse events carry (a finger's ids are small numbers; the mouse's is 1).
MOUSE_ID = 7041

TOUCH_JS = """(() => {
  if (window.__phototaxisTouch) return;  // a page that reconnects keeps one set of listeners
  window.__phototaxisTouch = true;
  const TAP_PX = %(tap_px)d, TAP_MS = %(tap_ms)d, DRAG_PX = %(drag_px)d;
  const LIT = %(lit)s, MOUSE_ID = %(mouse_id)d;
  const fingers = new Map();  // pointerId -> {x0, y0, t0, lamp, canvas, lastX, lastY, moved}
  const area = (c) => c.clientWidth * c.clientHeight;
  const sceneCanvas = (target) => {  // the scene's canvases are the page's largest (charts are small)
    if (!(target instanceof HTMLCanvasElement)) return null;
    const largest = Math.max(...[...document.querySelectorAll("canvas")].map(area));
    return area(target) >= 0.9 * largest ? target : null;
  };
  const lampLit = () => [...document.querySelectorAll("button")].some((b) => b.textContent.trim() === LIT);
  const click = (target, x, y) => {  // the mouse press and release viser sends as a click
    for (const type of ["pointerdown", "pointerup"]) {
      target.dispatchEvent(new PointerEvent(type, {
        bubbles: true, cancelable: true, composed: true, pointerId: MOUSE_ID, pointerType: "mouse",
        isPrimary: true, button: 0, buttons: type === "pointerdown" ? 1 : 0, clientX: x, clientY: y}));
    }
    window.__phototaxisTouchClicks = (window.__phototaxisTouchClicks || 0) + 1;
  };
  const ours = (event) => event.pointerType === "touch" && event.isTrusted;
  window.addEventListener("pointerdown", (event) => {
    if (!ours(event)) return;
    const canvas = sceneCanvas(event.target);
    if (!canvas) return;
    const lamp = fingers.size === 0 && lampLit();  // a second finger is the camera's
    if (fingers.size > 0) for (const f of fingers.values()) f.lamp = false;
    const now = performance.now();
    fingers.set(event.pointerId, {x0: event.clientX, y0: event.clientY, t0: now, lamp, canvas,
                                  lastX: event.clientX, lastY: event.clientY, moved: false});
    if (lamp) {
      event.stopImmediatePropagation();  // not the camera's: the lamp's
      click(canvas, event.clientX, event.clientY);
    }
  }, true);
  window.addEventListener("pointermove", (event) => {
    if (!ours(event)) return;
    const f = fingers.get(event.pointerId);
    if (!f) return;
    if (Math.hypot(event.clientX - f.x0, event.clientY - f.y0) > TAP_PX) f.moved = true;
    if (!f.lamp) return;
    event.stopImmediatePropagation();
    if (Math.hypot(event.clientX - f.lastX, event.clientY - f.lastY) >= DRAG_PX) {
      f.lastX = event.clientX; f.lastY = event.clientY;
      click(f.canvas, event.clientX, event.clientY);
    }
  }, true);
  const lift = (event, cancelled) => {
    if (!ours(event)) return;
    const f = fingers.get(event.pointerId);
    if (!f) return;
    fingers.delete(event.pointerId);
    if (f.lamp) {
      event.stopImmediatePropagation();
      if (!cancelled && (event.clientX !== f.lastX || event.clientY !== f.lastY)) {
        click(f.canvas, event.clientX, event.clientY);  // where the finger left the floor
      }
    } else if (!cancelled && !f.moved && performance.now() - f.t0 <= TAP_MS) {
      // After viser has had the finger's release (this listener runs first): until then the finger's
      // press is viser's gesture under way, and a press of the mouse would be ignored.
      setTimeout(() => click(f.canvas, f.x0, f.y0), 0);
    }
  };
  window.addEventListener("pointerup", (event) => lift(event, false), true);
  window.addEventListener("pointercancel", (event) => lift(event, true), true);
})();""" % {"tap_px": TAP_PX, "tap_ms": TAP_MS, "drag_px": DRAG_PX,
            "lit": json.dumps(LAMP_LIT_LABEL), "mouse_id": MOUSE_ID}
