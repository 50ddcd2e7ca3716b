// The page reports the frames it draws, so the server sends it no more than it draws. Sent to each page at
// connect (sandbox/app/web/gate.py); sandbox/app/web/pacing.py says why, fills in each setting (a $ and a
// name) and holds CLIENT, the table of what this relies on in viser's client: its markup, and VISER below.
(() => {
  window.__phototaxisDrawn = $address;  // a reconnected page reports under its new token
  window.__phototaxisSpoke = false;  // ... and says once how it draws under it
  if (window.__phototaxisReporting) return;
  window.__phototaxisReporting = true;
  let drew = false, asking = false, busy = false, last = null, calmSince = null;
  const proto = window.WebGL2RenderingContext && WebGL2RenderingContext.prototype;
  if (!proto) return;
  // The calls with which viser's scene (three.js) draws.
  const VISER = {draws: ["drawArrays", "drawElements", "drawArraysInstanced", "drawElementsInstanced"]};
  for (const name of VISER.draws) {
    const draw = proto[name];
    if (typeof draw !== "function") continue;
    proto[name] = function (...args) { drew = true; return draw.apply(this, args); };
  }
  const ask = (suffix) => {
    asking = true;
    window.__phototaxisSpoke = true;
    fetch(window.__phototaxisDrawn + suffix, {cache: "no-store", credentials: "same-origin"})
      .catch(() => {}).finally(() => { asking = false; });
  };
  const tick = (now) => {
    if (last !== null && now - last > $busy_gap_ms) {
      busy = true;
      calmSince = null;
    } else if (busy || !window.__phototaxisSpoke) {  // (a page that keeps up from the start says so once)
      calmSince = calmSince === null ? now : calmSince;
      if (now - calmSince > 1000 && !asking) {
        busy = false;
        ask($calm);
      }
    }
    last = now;
    if (busy && drew && !asking) {
      drew = false;
      ask("");
    } else if (!busy) {
      drew = false;  // a draw while keeping up needs no report
    }
    requestAnimationFrame(tick);
  };
  requestAnimationFrame(tick);
})();
