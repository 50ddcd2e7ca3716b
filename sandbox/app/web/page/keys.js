// Keys the page gives a meaning keep it: viser's camera does not also move on them. Sent to each page at
// connect (sandbox/app/web/gate.py); sandbox/app/web/page_keys.py says why, fills in each setting (a $ and a
// name) and holds CLIENT, the table of what this relies on in viser's client: its markup, and VISER below.
(() => {
  if (window.__phototaxisKeysKept) return;  // a page that reconnects keeps the one pair of listeners
  window.__phototaxisKeysKept = true;
  // viser's camera turns on the arrows; the controls whose own keys they are; the hotkeys that move it too.
  const VISER = {arrows: ["ArrowUp", "ArrowDown", "ArrowLeft", "ArrowRight"], controls: $controls, hotkeys: $hotkeys};
  const ARROWS = new Set(VISER.arrows);
  const CONTROLS = VISER.controls;
  const HOTKEYS = new Set(VISER.hotkeys);
  document.body.addEventListener("keydown", (event) => {
    const target = event.target;
    if (ARROWS.has(event.code) && target instanceof Element && target.closest(CONTROLS)) {
      event.stopPropagation();  // the control had it; viser's camera, listening on the document, does not
    }
  });
  document.documentElement.addEventListener("keydown", (event) => {
    if (HOTKEYS.has(event.code)) event.stopPropagation();  // the hotkeys here had it; the camera does not
  });
})();
