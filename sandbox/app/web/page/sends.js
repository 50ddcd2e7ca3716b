// Every click a page makes reaches the server, however busy the page is. Sent to each page at
// connect (sandbox/app/web/gate.py); sandbox/app/web/page_sends.py says why, fills in each setting (a $ and a
// name) and holds CLIENT, the table of what this relies on in viser's client: its markup, and VISER below.
(() => {
  if (window.__phototaxisSendsKept) return;  // a page that reconnects keeps the one set of hooks
  window.__phototaxisSendsKept = true;
  const worker = window.Worker && Worker.prototype;  // viser's websocket lives in a worker
  if (!worker) return;
  // The longest timer taken for a throttle's: viser's throttles wait 20 and 50 ms.
  const VISER = {mostMs: $most_ms};
  const MOST_MS = VISER.mostMs;
  const due = new Map();  // a throttle's timer id -> {at, run}
  let justSent = false;  // a message went to the server in this turn of the script
  const post = worker.postMessage;
  worker.postMessage = function (...args) {
    justSent = true;
    queueMicrotask(() => { justSent = false; });
    return post.apply(this, args);
  };
  const setTimer = window.setTimeout, clearTimer = window.clearTimeout;
  window.setTimeout = function (fn, ms, ...rest) {
    if (!justSent || typeof fn !== "function" || !(ms > 0 && ms <= MOST_MS)) {
      return setTimer.call(window, fn, ms, ...rest);
    }
    let id = null;
    const run = () => { if (due.delete(id)) fn(...rest); };  // once, whoever runs it first
    id = setTimer.call(window, run, ms);
    due.set(id, {at: performance.now() + ms, run});
    return id;
  };
  window.clearTimeout = function (id) {
    due.delete(id);
    return clearTimer.call(window, id);
  };
  const run = (all) => {  // the throttles' timers: every one (all), or those due by now
    const now = performance.now();
    for (const [id, timer] of [...due]) {
      if (!all && timer.at > now) continue;
      clearTimer.call(window, id);
      try { timer.run(); } catch (error) { setTimer.call(window, () => { throw error; }, 0); }
    }
  };
  const options = {capture: true, passive: true};
  // A press or a release: every held message goes now, so this one's click is sent, not held and merged.
  for (const type of ["pointerdown", "pointerup"]) window.addEventListener(type, () => run(true), options);
  // A move keeps the throttle's pace (a drag's updates): only what is due.
  window.addEventListener("pointermove", () => run(false), options);
})();
