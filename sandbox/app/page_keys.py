"""Arrow keys pressed on a panel control stay with that control.

viser's client moves its camera on W A S D Q E and turns it on the arrow
keys, wherever they are pressed except in a text field (its
``isFormElement``: input, textarea, select). A slider's thumb is none of
these, so an arrow pressed to nudge *Steps per frame* moved the slider and
also turned the view, 50 degrees a second while held: 20 degrees for one
press of 0.15 s, measured. A class would see the arena turn when the
teacher changed the speed, and the floor a click lands on would be turned
with it.

:data:`KEYS_JS`, sent to each page at connect (:mod:`sandbox.app.gate`),
stops an arrow key on its way up from a control that uses arrows (a
slider, a tab, a radio, a list's option, a menu). The control has already
had the key (React hears it at its root, inside the body) and viser's
camera listener on the document never does. Letters are left alone: no
control here uses them, and the page's hotkeys (space, s, r, p) listen on
the document too. With the focus on the floor or on a button, the arrows
still turn the camera, as viser documents.
"""

from __future__ import annotations

import json

#: Controls whose own keys the arrows are (ARIA roles, as Mantine's controls carry them).
ARROW_CONTROLS = ("slider", "tab", "radio", "option", "listbox", "menuitem", "combobox", "spinbutton")

KEYS_JS = """(() => {
  if (window.__phototaxisArrowsKept) return;  // a page that reconnects keeps the one listener
  window.__phototaxisArrowsKept = true;
  const ARROWS = new Set(["ArrowUp", "ArrowDown", "ArrowLeft", "ArrowRight"]);
  const CONTROLS = %(selector)s;
  document.body.addEventListener("keydown", (event) => {
    const target = event.target;
    if (ARROWS.has(event.code) && target instanceof Element && target.closest(CONTROLS)) {
      event.stopPropagation();  // the control had it; viser's camera, listening on the document, does not
    }
  });
})();""" % {"selector": json.dumps(",".join(f'[role="{role}"]' for role in ARROW_CONTROLS))}
