// Touch on the floor acts as a click does. Sent to each page at
// connect (sandbox/app/web/gate.py); sandbox/app/web/page_touch.py says why, fills in each setting (a $ and a
// name) and holds CLIENT, the table of what this relies on in viser's client: its markup, and VISER below.
(() => {
  if (window.__phototaxisTouch) return;  // a page that reconnects keeps one set of listeners
  window.__phototaxisTouch = true;
  const TAP_PX = $tap_px, TAP_MS = $tap_ms, DRAG_PX = $drag_px;
  const LIT = $lit, MOUSE_ID = $mouse_id;
  // What viser's scene hears as a click: a mouse's press and release (a finger's are its camera's).
  const VISER = {click: ["pointerdown", "pointerup"], pointer: "mouse"};
  const [PRESS, RELEASE] = VISER.click;
  const fingers = new Map();  // pointerId -> {x0, y0, t0, lamp, canvas, lastX, lastY, moved}
  const area = (c) => c.clientWidth * c.clientHeight;
  const sceneCanvas = (target) => {  // the scene's canvases are the page's largest (charts are small)
    if (!(target instanceof HTMLCanvasElement)) return null;
    const largest = Math.max(...[...document.querySelectorAll("canvas")].map(area));
    return area(target) >= 0.9 * largest ? target : null;
  };
  const lampLit = () => [...document.querySelectorAll("button")].some((b) => b.textContent.trim() === LIT);
  const click = (target, x, y) => {  // the mouse press and release viser sends as a click
    for (const type of [PRESS, RELEASE]) {
      target.dispatchEvent(new PointerEvent(type, {
        bubbles: true, cancelable: true, composed: true, pointerId: MOUSE_ID, pointerType: VISER.pointer,
        isPrimary: true, button: 0, buttons: type === PRESS ? 1 : 0, clientX: x, clientY: y}));
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
})();
