"""Keys the page gives a meaning stay with that meaning: viser's camera
does not also move on them.

viser's client moves its camera on W A S D Q E and turns it on the arrow
keys, wherever they are pressed except in a text field (its
``isFormElement``: input, textarea, select), for every frame drawn while
a key is down, however long that frame took. Two of them clash with this
page, as measured:

- **Arrows on a slider.** A slider's thumb is not a text field, so an
  arrow pressed to nudge *Steps per frame* moved the slider and also turned
  the view, 50 degrees a second while held: 20 degrees for one press of
  0.15 s. A class would see the arena turn when the teacher changed the
  speed, and the floor a click lands on would be turned with it.
- **s, the Step key** (the Run folder's hotkeys: space, s, r, p). It also
  moved the camera back (south, seen from above): 0.7-2.2 m for one press.

:data:`KEYS_JS`, sent to each page at connect (:mod:`sandbox.app.web.gate`),
stops an arrow on its way up from a control that uses arrows (a slider, a
tab, a radio, a list's option, a menu), and the Step key once the page's
hotkeys have had it. The control has already had the arrow (React hears it
at its root, inside the body); the hotkeys listen on the document's root
element, where the Step key is stopped for the listeners further up; viser's
camera listens on the document itself, above both, and hears neither. With
the focus on the floor or on a button, the arrows still turn the camera and
W A D Q E still move it, as viser documents.
"""

from __future__ import annotations

import json

#: Controls whose own keys the arrows are (ARIA roles, as Mantine's controls carry them).
ARROW_CONTROLS = ("slider", "tab", "radio", "option", "listbox", "menuitem", "combobox", "spinbutton")
#: The page's hotkeys that are also viser's camera keys (KeyboardEvent.code): s steps (sandbox.app.panel.run).
HOTKEYS_NOT_CAMERA = ("KeyS",)

KEYS_JS = """(() => {
  if (window.__phototaxisKeysKept) return;  // a page that reconnects keeps the one pair of listeners
  window.__phototaxisKeysKept = true;
  const ARROWS = new Set(["ArrowUp", "ArrowDown", "ArrowLeft", "ArrowRight"]);
  const CONTROLS = %(selector)s;
  const HOTKEYS = new Set(%(hotkeys)s);
  document.body.addEventListener("keydown", (event) => {
    const target = event.target;
    if (ARROWS.has(event.code) && target instanceof Element && target.closest(CONTROLS)) {
      event.stopPropagation();  // the control had it; viser's camera, listening on the document, does not
    }
  });
  document.documentElement.addEventListener("keydown", (event) => {
    if (HOTKEYS.has(event.code)) event.stopPropagation();  // the hotkeys here had it; the camera does not
  });
})();""" % {"selector": json.dumps(",".join(f'[role="{role}"]' for role in ARROW_CONTROLS)),
           "hotkeys": json.dumps(list(HOTKEYS_NOT_CAMERA))}
