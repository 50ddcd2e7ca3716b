"""Every click a page makes reaches the server, however busy the page is.

viser's client sends scene clicks, clicks on a node and drag updates through
a *throttled sender* (``makeThrottledMessageSender``): it sends a message at
once, then holds the next ones for 20 ms (scene clicks) or 50 ms (node clicks,
drags) and, when a ``setTimeout`` of that length fires, sends only the newest
of those it held. The timer is what lets the next message go at once again.

On a busy page the timer fires late. Measured in headless Chromium at
1600 x 1000 drawing the default world in software (``phototaxis serve``):
the 20 ms timer of the first click fired after 10.4 s, while the page went
on handling one press a second. The clicks in between were held and replaced
by each newer one, and six clicks on the floor 2 s apart gave the server 2
(the first, and the last once the timer fired). Drags suffered the same: an
update, then nothing until the release.

:data:`SENDS_JS`, sent to each page at connect (:mod:`sandbox.app.web.gate`),
runs such a timer itself, before the page's own handlers hear the pointer:

- **on a press or a release, at once**, due or not. Clicks are discrete, and
  a throttle is for a stream: a click must never be merged into the next.
  This matters when the page was busy: the presses that waited for it are
  then handled one after the other within a millisecond or two, inside one
  20 ms window, and with only the due timers run, the middle one of three
  clicks was replaced by the last (29 of 30 clicks at a person's pace on a
  loaded machine, tests/test_browser_editing.py);
- **on a move, once it is due**, instead of when the browser gets round to
  it: a drag's updates keep the throttle's pace.

It only does this for the timers that follow a message to the server in the
same turn of the page's script, at most :data:`MOST_MS` long: the throttles'
timers. A page that is not busy, and not clicked, runs them on time as
before, and nothing else in the page changes.
"""

from __future__ import annotations

#: The longest timer treated as a throttle's (ms): viser's are 20 and 50.
MOST_MS = 100

SENDS_JS = """(() => {
  if (window.__phototaxisSendsKept) return;  // a page that reconnects keeps the one set of hooks
  window.__phototaxisSendsKept = true;
  const worker = window.Worker && Worker.prototype;  // viser's websocket lives in a worker
  if (!worker) return;
  const MOST_MS = %(most_ms)d;
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
})();""" % {"most_ms": MOST_MS}
