"""Keys the page gives a meaning stay with that meaning: viser's camera
does not also move on them.
The script runs in the page; the server sends it as a page connects, on viser's event loop.

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

:data:`KEYS_JS` (``page/keys.js``), sent to each page at connect (:mod:`sandbox.app.web.gate`),
stops an arrow on its way up from a control that uses arrows (a slider, a
tab, a radio, a list's option, a menu), and the Step key once the page's
hotkeys have had it. The control has already had the arrow (React hears it
at its root, inside the body); the hotkeys listen on the document's root
element, where the Step key is stopped for the listeners further up; viser's
camera listens on the document itself, above both, and hears neither. With
the focus on the floor or on a button, the arrows still turn the camera and
W A D Q E still move it, as viser documents.

:data:`CLIENT` is what the script relies on in viser's client, checked against the installed viser's
bundle (:mod:`sandbox.app.web.client_seam`).
"""

from __future__ import annotations

from sandbox.app.web.client_seam import Relies, script

#: Controls whose own keys the arrows are (ARIA roles, as Mantine's controls carry them). viser 1.1.1 has
#: no radio or spinbutton role: its radios and number fields are inputs, which its camera skips already.
ARROW_CONTROLS = ("slider", "tab", "option", "listbox", "menuitem", "combobox")
#: The page's hotkeys that are also viser's camera keys (KeyboardEvent.code): s steps (sandbox.app.panel.run).
HOTKEYS_NOT_CAMERA = ("KeyS",)

KEYS_JS = script("keys.js", controls=",".join(f'[role="{role}"]' for role in ARROW_CONTROLS),
                 hotkeys=list(HOTKEYS_NOT_CAMERA))

# Where viser's client listens for keys: its camera on the document, for these keys (not in a text field).
_CAMERA_KEYS = (r"new Set\(\[`KeyW`,`KeyA`,`KeyS`,`KeyD`,`KeyQ`,`KeyE`,"
                r"`ArrowUp`,`ArrowDown`,`ArrowLeft`,`ArrowRight`\]\)")
_CAMERA_ON_DOCUMENT = r"document\.addEventListener\(`keydown`,[\w$]+\),document\.addEventListener\(`keyup`,"
_NOT_IN_TEXT_FIELDS = r"===`INPUT`\|\|[\w$]+===`TEXTAREA`\|\|[\w$]+===`SELECT`\|\|[\w$]+\.isContentEditable"
_ARROW = ("viser turns its camera on the arrow keys, listening on the document, wherever they are pressed but "
          "in a text field: the script stops them on the body, below the document, after the control had them")
_ROLE = "a control that takes the arrows as its own: its arrows are stopped before viser's camera hears them"

#: What keys.js relies on in viser's client (sandbox.app.web.client_seam).
CLIENT = (
    Relies("ArrowUp", _ARROW, found=(_CAMERA_KEYS, _CAMERA_ON_DOCUMENT, _NOT_IN_TEXT_FIELDS)),
    Relies("ArrowDown", _ARROW, found=(_CAMERA_KEYS, _CAMERA_ON_DOCUMENT)),
    Relies("ArrowLeft", _ARROW, found=(_CAMERA_KEYS, _CAMERA_ON_DOCUMENT)),
    Relies("ArrowRight", _ARROW, found=(_CAMERA_KEYS, _CAMERA_ON_DOCUMENT)),
    Relies("KeyS", "viser moves its camera back on s, listening on the document; the page's hotkeys (Mantine's "
           "useHotkeys) listen on the document's root element, below it: the script stops s there",
           found=(_CAMERA_KEYS, _CAMERA_ON_DOCUMENT, r"document\.documentElement\.addEventListener\(`keydown`,")),
    Relies('[role="slider"]', f"Mantine's Slider (viser's sliders) on its thumb: {_ROLE}", found=(r"role:`slider`",)),
    Relies('[role="tab"]', f"Mantine's Tabs (viser's tab groups): {_ROLE}", found=(r"role:`tab`",)),
    Relies('[role="option"]', f"a dropdown's option (Mantine's Combobox): {_ROLE}", found=(r"role:`option`",)),
    Relies('[role="listbox"]', f"a dropdown's list (Mantine's Combobox): {_ROLE}", found=(r"role:`listbox`",)),
    Relies('[role="menuitem"]', f"an item of a Mantine Menu: {_ROLE}", found=(r"role:`menuitem`",)),
    Relies('[role="combobox"]', f"a dropdown's field (Mantine's Select): {_ROLE}", found=(r"role:`combobox`",)),
)
