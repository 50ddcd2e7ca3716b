"""What a phone's page lays out differently, and a notice that leaves the floor (issue 41, item 5).
The script runs in the page; the server sends it as a page connects, on viser's event loop.

viser picks its layout from the page's width: under its ``xs`` breakpoint
(36em, 576 px) the panel is a bottom sheet, 20em wide, open, over the
arena's lower right, with every folder in it; its theme has no setting for
this. Measured at 390x844 in Chromium: the sheet covered the lower half of
the floor, and *Be the light* and *Challenge* sat below about 15 strategy
controls. viser's "Software WebGL rendering detected" notice (its own,
shown whenever the page draws in software, not configurable) covered the
top third of the screen until closed.

:data:`LAYOUT_JS` (``page/layout.js``), sent to each page at connect (:mod:`sandbox.app.web.gate`):

- **A drawer.** On a narrow page the sheet spans the width and starts
  closed (its own handle, "Phototaxis sandbox", opens and closes it), so
  the arena is whole; the framing already fits the arena to the width,
  at the page's top, and the open drawer stops below it.
- **One tap away.** Two buttons over the floor's lower left, under the
  open drawer: *Be the light* presses the panel's own button (its label
  follows the panel's: *Give the light back*), *Challenge* opens the
  drawer at the Challenge folder. They act through the panel's controls,
  so the server checks them as it checks the panel.
- **A folder brought to the page.** ``window.__phototaxisOpenFolder(title,
  inside)`` opens a folder of the panel (the drawer first, on a phone) and
  scrolls its title to the panel's top: the Challenge shortcut's, and what
  the server asks of one page (:mod:`sandbox.app.web.page_open`: the Result
  folder after a run to the end). viser 1.1.1 opens a folder only when it
  is first built (``expand_by_default``), and for every page at once.
- **The notice goes.** The software-rendering notice closes after
  :data:`NOTICE_SECONDS`, on every width.
- **Tap, not space.** On a page with a touch screen (a coarse pointer) or a
  phone's width, the title card's last line (:mod:`sandbox.app.panel.presenter`)
  says :data:`TAP_PLAY` instead of :data:`PRESS_PLAY`: a phone has no space
  bar. Only the page knows it is touched; the server sends every card the
  keyboard's words, which a desktop page keeps.
- **Notices whole.** A notice is as tall as its text, up to the window's
  height less its margins, and scrolls beyond (Mantine holds each at 200
  px with its overflow hidden: the *Goal changed* of a drawn F lost the
  top and bottom of its 242 px; issue 56, item 1).
- **Lists fit the screen.** A dropdown's list opens as a sheet along the
  screen's bottom, the screen's width (8 px margins), at most half its
  height. viser's lists are placed for the 20em sheet and do not flip: at
  390x844 the *group* list of Population and physics opened at x 243-501
  and y 933 and more, off the screen's right edge and below its bottom.

:data:`CLIENT` is what the script relies on in viser's client, checked against the installed viser's
bundle (:mod:`sandbox.app.web.client_seam`).
"""

from __future__ import annotations

from sandbox.app.web.client_seam import MANTINE, TEXT, Relies, script

#: viser's breakpoint for its phone layout (Mantine's xs: 36em at 16 px).
NARROW = "(max-width: 576px)"
#: Seconds viser's software-rendering notice stays before the page closes it.
NOTICE_SECONDS = 4.0
#: The notice's title, as viser 1.1.1 shows it.
SOFTWARE_NOTICE = "Software WebGL rendering detected"
#: The lamp's button labels (sandbox.app.panel.lamp) and the Challenge folder's (sandbox.app.panel.challenge).
LAMP_LABELS = ("Be the light", "Give the light back")
CHALLENGE = "Challenge"
START_ROUND = "Start a round"
#: The id of the shortcuts' bar (tests find it by it).
SHORTCUTS_ID = "phototaxis-shortcuts"
#: The title card's last line for a controlling page: as sent (a keyboard), and as a touch page shows it.
PRESS_PLAY = "Press Play (space) to start."
TAP_PLAY = "Tap Play to start."
#: A page touched rather than pointed at: its primary pointer is a finger.
TOUCH = "(pointer: coarse)"

LAYOUT_JS = script("layout.js", narrow=NARROW, notice=SOFTWARE_NOTICE, notice_ms=round(1000 * NOTICE_SECONDS),
                   lamp=list(LAMP_LABELS), challenge=CHALLENGE, start=START_ROUND, bar=SHORTCUTS_ID,
                   touch=TOUCH, press=PRESS_PLAY, tap=TAP_PLAY)

# viser's phone sheet (its BottomPanel): a Paper fixed at the page's bottom, 20em wide, its height animated.
_SHEET = (r"style:\{boxSizing:`border-box`,zIndex:10,position:`fixed`,bottom:0,right:0,margin:0,"
          r"minHeight:`3\.5em`,maxHeight:`60%`,width:`20em`,transition:`height 0\.3s linear`\}")
# ... its handle (a Box, a div): the first thing in it styled cursor: pointer, as tall as the closed sheet
_HANDLE = r"style:\{cursor:`pointer`,position:`relative`,[^{}]*height:`3\.5em`\}"
# A folder's title: a Paper styled cursor: pointer (a folder with something in it), its label, then a chevron.
_FOLDER_TITLE = r"style:\{cursor:[\w$]+\?void 0:`pointer`\},onClick:[\w$]+,children:\[[\w$]+,"
_LIST = ("a dropdown's list (viser's dropdown is Mantine's Select, its list a Combobox's): placed by the script "
         "on a phone")

#: What layout.js relies on in viser's client (sandbox.app.web.client_seam).
CLIENT = (
    Relies(".mantine-Notification-root", "viser's notices are Mantine's Notifications: the software-rendering "
           "one is found by its title", MANTINE),
    Relies(".mantine-Notification-closeButton", "a notice's close button, which the script clicks", MANTINE),
    Relies(".mantine-Paper-root", "viser's phone sheet and each folder's title are Mantine Papers: the sheet the "
           "one fixed at the page's bottom, a title the one whose first child is its label's text (a click on it "
           "opens or closes the folder)", MANTINE, found=(_SHEET, _FOLDER_TITLE)),
    Relies(".mantine-Combobox-dropdown", _LIST, MANTINE),
    Relies(".mantine-Select-dropdown", _LIST, MANTINE),
    Relies('div[style*="cursor: pointer"]', "the sheet's handle, its first element styled cursor: pointer: a click "
           "opens or closes the sheet, and the closed sheet is as tall as it (3.5em)", found=(_HANDLE,)),
    Relies('div[style*="width: 20em"]', "the sheet's contents, a Box as wide as the sheet (20em): widened with it",
           found=(r"style:\{width:`20em`\}",)),
    Relies('[role="dialog"]', "the title card is a viser modal, Mantine's Modal: its content a section with role "
           "dialog", found=(r"component:`section`,role:`dialog`",)),
    Relies("button", "viser's buttons are Mantine's (an UnstyledButton, a <button>) with their label as their "
           "text: the script presses the panel's by their labels",
           found=(r"\.displayName=`@mantine/core/Button`", r"component:[\w$]+=`button`")),
    Relies(NARROW, "viser lays the page out for a phone under Mantine's xs breakpoint, 36em (576 px at 16 px)",
           found=(r"\(max-width: \$\{[\w$]+\(\)\.breakpoints\.xs\}\)", r"breakpoints:\{xs:`36em`")),
    Relies(SOFTWARE_NOTICE, "the title of viser's notice that the page draws in software", TEXT),
    Relies("fixed", "the sheet is the Paper whose style has position fixed ...", found=(_SHEET,)),
    Relies("0px", "... and bottom 0", found=(_SHEET,)),
    Relies("350", "how long (ms) the script waits for the drawer, then a folder, to open: viser's sheet animates "
           "its height over 0.3 s, a folder (Mantine's Collapse) over 200 ms",
           found=(_SHEET, r"transitionDuration:200,transitionTimingFunction:`ease`,animateOpacity")),
)
