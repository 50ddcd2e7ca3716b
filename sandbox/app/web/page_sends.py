"""Every click a page makes reaches the server, however busy the page is.
The script runs in the page; the server sends it as a page connects, on viser's event loop.

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

:data:`SENDS_JS` (``page/sends.js``), sent to each page at connect (:mod:`sandbox.app.web.gate`),
runs such a timer itself, before the page's own handlers hear the pointer:

- **on a press or a release, at once**, due or not. Clicks are discrete, and
  a throttle is for a stream: a click must never be merged into the next.
  This matters when the page was busy: the presses that waited for it are
  then handled one after the other within a millisecond or two, inside one
  20 ms window, and with only the due timers run, the middle one of three
  clicks was replaced by the last (29 of 30 clicks at a person's pace on a
  loaded machine, tests/browser/test_browser_editing.py);
- **on a move, once it is due**, instead of when the browser gets round to
  it: a drag's updates keep the throttle's pace.

It only does this for the timers that follow a message to the server in the
same turn of the page's script, at most :data:`MOST_MS` long: the throttles'
timers. A page that is not busy, and not clicked, runs them on time as
before, and nothing else in the page changes.

:data:`CLIENT` is what the script relies on in viser's client, checked against the installed viser's
bundle (:mod:`sandbox.app.web.client_seam`).
"""

from __future__ import annotations

from sandbox.app.web.client_seam import Relies, script

#: The longest timer treated as a throttle's (ms): viser's are 20 and 50.
MOST_MS = 100

SENDS_JS = script("sends.js", most_ms=MOST_MS)

#: viser's throttled sender: it sends, then arms its timer in the same turn; its cancel clears the timer.
_THROTTLE = r"\.sendMessage\([\w$]+\),[\w$]+=!1,[\w$]+=!1,[\w$]+=setTimeout\(\(\)=>\{"
_CANCEL = (r"clearTimeout\([\w$]+\),[\w$]+=null\),[\w$]+=!0,[\w$]+=!1,[\w$]+=null\}"
           r"return\{send:[\w$]+,flush:[\w$]+,cancel:")

#: What sends.js relies on in viser's client (sandbox.app.web.client_seam).
CLIENT = (
    Relies("Worker.prototype", "viser's client talks to its websocket in a worker: every message to the "
           "server is the worker's postMessage({type: \"send\", message}), which the script marks as sent",
           found=(r"new Worker\(", r"\{type:`send`,message:[\w$]+\}")),
    Relies("window.setTimeout", "viser's throttled sender (makeThrottledMessageSender) sends a message, then "
           "arms its throttle's timer with setTimeout in the same turn: the timers the script runs on time",
           found=(_THROTTLE,)),
    Relies("window.clearTimeout", "the sender's cancel clears its timer: the script forgets it too",
           found=(_CANCEL,)),
    Relies(str(MOST_MS), "the longest timer taken for a throttle's (ms): viser's throttles are 20 ms (scene "
           "clicks, the camera) and 50 ms (node clicks, drags, controls), each a use of its hook "
           "useThrottledMessageSender(ms) or of the sender itself (ms after its viewer)",
           found=(r"\((\d+)\)\.send\b", r"\{send:[\w$]+,flush:[\w$]+\}=[\w$]+\((?:[\w$]+,)?(\d+)\)"),
           values=(20, 50)),
)
