"""What a phone's page lays out differently, and a notice that leaves the floor (issue 41, item 5).

viser picks its layout from the page's width: under its ``xs`` breakpoint
(36em, 576 px) the panel is a bottom sheet, 20em wide, open, over the
arena's lower right, with every folder in it; its theme has no setting for
this. Measured at 390x844 in Chromium: the sheet covered the lower half of
the floor, and *Be the light* and *Challenge* sat below about 15 strategy
controls. viser's "Software WebGL rendering detected" notice (its own,
shown whenever the page draws in software, not configurable) covered the
top third of the screen until closed.

:data:`LAYOUT_JS`, sent to each page at connect (:mod:`sandbox.app.web.gate`):

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
- **Lists fit the screen.** A dropdown's list opens as a sheet along the
  screen's bottom, the screen's width (8 px margins), at most half its
  height. viser's lists are placed for the 20em sheet and do not flip: at
  390x844 the *group* list of Population and physics opened at x 243-501
  and y 933 and more, off the screen's right edge and below its bottom.
"""

from __future__ import annotations

import json

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

LAYOUT_JS = """(() => {
  if (window.__phototaxisLayout) return;  // a page that reconnects keeps one observer
  window.__phototaxisLayout = true;
  const NARROW = window.matchMedia(%(narrow)s), TOUCH = window.matchMedia(%(touch)s);
  const PRESS_PLAY = %(press)s, TAP_PLAY = %(tap)s;
  const NOTICE = %(notice)s, NOTICE_MS = %(notice_ms)d;
  const LAMP = %(lamp)s, CHALLENGE = %(challenge)s, START = %(start)s, BAR = %(bar)s;
  const closing = new WeakSet(), drawers = new WeakSet();
  const button = (labels) => [...document.querySelectorAll("button")].find(  // the panel's, not ours
    (b) => labels.includes(b.textContent.trim()) && !b.closest("#" + BAR));
  const shown = (el) => !!el && el.getBoundingClientRect().height > 0;

  // viser's software-rendering notice: closed after a few seconds.
  const closeNotice = () => {
    for (const note of document.querySelectorAll(".mantine-Notification-root")) {
      if (closing.has(note) || !note.textContent.includes(NOTICE)) continue;
      closing.add(note);
      setTimeout(() => note.querySelector(".mantine-Notification-closeButton")?.click(), NOTICE_MS);
    }
  };

  // The phone's bottom sheet (a fixed Paper at the page's bottom): full width, closed at first.
  const sheet = () => [...document.querySelectorAll(".mantine-Paper-root")].find(
    (p) => p.style.position === "fixed" && p.style.bottom === "0px");
  const handleOf = (paper) => paper.querySelector("div[style*='cursor: pointer']");
  const sheetOpen = (paper) => paper.getBoundingClientRect().height > 1.5 * handleOf(paper).getBoundingClientRect().height;
  const makeDrawer = () => {
    const paper = sheet();
    if (!paper || drawers.has(paper) || !handleOf(paper)) return;
    drawers.add(paper);
    paper.style.width = "100%%";
    // Open, it ends where the arena begins: a phone frames the arena as wide as the page at its top
    // (sandbox.app.view.scene.top_down_camera), so the floor's square is 100vw tall. viser's sheet took 60 %%.
    paper.style.maxHeight = "max(40vh, calc(100vh - 100vw - 4px))";
    for (const box of paper.querySelectorAll("div[style*='width: 20em']")) box.style.width = "100%%";  // its contents
    if (sheetOpen(paper)) handleOf(paper).click();  // closed: the arena whole until the drawer is opened
  };

  // A folder opened (the drawer first) and its title scrolled to the panel's top; ``inside``: the labels
  // of a button it holds, shown once it is open (a click on the title of an open folder would close it).
  const openFolder = (name, inside) => {
    const paper = sheet();
    if (paper && !sheetOpen(paper)) handleOf(paper).click();
    setTimeout(() => {
      const title = [...document.querySelectorAll(".mantine-Paper-root")].find(  // a folder's label: text, chevron
        (e) => e.firstChild?.nodeType === Node.TEXT_NODE && e.firstChild.textContent.trim() === name);
      if (!title) return;
      if (!shown(button(inside))) title.click();
      setTimeout(() => title.scrollIntoView({block: "start", behavior: "smooth"}), 350);
    }, 350);
  };
  window.__phototaxisOpenFolder = openFolder;  // for the server's scripts to one page (sandbox.app.web.page_open)

  // Be the light and Challenge, one tap away on a phone.
  const openChallenge = () => openFolder(CHALLENGE, [START]);
  const shortcuts = () => {
    let bar = document.getElementById(BAR);
    if (!NARROW.matches) {
      if (bar) bar.style.display = "none";
      return;
    }
    if (!bar) {
      bar = document.createElement("div");
      bar.id = BAR;
      bar.style.cssText = "position: fixed; left: 8px; bottom: calc(3.5em + 10px); z-index: 9; display: flex; " +
                          "gap: 8px; font: 600 15px system-ui, sans-serif;";
      const make = (name, act) => {
        const b = document.createElement("button");
        b.type = "button";
        b.dataset.shortcut = name;
        b.textContent = name;
        b.style.cssText = "padding: 10px 14px; border-radius: 8px; border: 0; color: #111; " +
                          "background: rgb(255, 190, 40); box-shadow: 0 2px 6px rgba(0,0,0,.5);";
        b.addEventListener("click", act);
        bar.appendChild(b);
        return b;
      };
      make(LAMP[0], () => button(LAMP)?.click());
      make(CHALLENGE, openChallenge);
      document.body.appendChild(bar);
    }
    bar.style.display = "flex";
    const lamp = button(LAMP);
    const first = bar.firstElementChild;
    if (lamp && first.textContent !== lamp.textContent.trim()) first.textContent = lamp.textContent.trim();
    const paper = sheet();
    bar.style.visibility = paper && sheetOpen(paper) ? "hidden" : "visible";  // under the open drawer
  };

  // The title card's words for this page: a finger taps Play, a keyboard has space (and a desktop window
  // narrowed, then widened again, gets its keyboard's words back).
  const cardWords = () => {
    const [from, to] = TOUCH.matches || NARROW.matches ? [PRESS_PLAY, TAP_PLAY] : [TAP_PLAY, PRESS_PLAY];
    for (const card of document.querySelectorAll("[role='dialog']")) {
      const texts = document.createTreeWalker(card, NodeFilter.SHOW_TEXT);
      for (let text = texts.nextNode(); text; text = texts.nextNode()) {
        if (text.nodeValue.trim() === from) text.nodeValue = to;
      }
    }
  };

  // A dropdown's list on a narrow page: a sheet along the bottom of the screen (it wins over the inline
  // place viser's page computes, which is off the screen in the drawer).
  const lists = document.createElement("style");
  lists.textContent = "@media " + NARROW.media + " { .mantine-Combobox-dropdown, .mantine-Select-dropdown {" +
    " position: fixed !important; left: 8px !important; right: 8px !important; top: auto !important;" +
    " bottom: 8px !important; width: auto !important; max-height: 50vh !important; overflow-y: auto !important; } }";
  document.head.appendChild(lists);

  const look = () => {
    closeNotice();
    if (NARROW.matches) makeDrawer();
    shortcuts();
    cardWords();
  };
  let queued = false;
  new MutationObserver(() => {
    if (queued) return;
    queued = true;
    requestAnimationFrame(() => { queued = false; look(); });
  }).observe(document.body, {childList: true, subtree: true, characterData: true});
  NARROW.addEventListener("change", look);
  TOUCH.addEventListener("change", look);
  setInterval(() => { if (NARROW.matches) look(); }, 500);  // the drawer opened or closed (a style, unobserved)
  look();
})();""" % {"narrow": json.dumps(NARROW), "notice": json.dumps(SOFTWARE_NOTICE),
            "notice_ms": round(1000 * NOTICE_SECONDS), "lamp": json.dumps(list(LAMP_LABELS)),
            "challenge": json.dumps(CHALLENGE), "start": json.dumps(START_ROUND), "bar": json.dumps(SHORTCUTS_ID),
            "touch": json.dumps(TOUCH), "press": json.dumps(PRESS_PLAY), "tap": json.dumps(TAP_PLAY)}
