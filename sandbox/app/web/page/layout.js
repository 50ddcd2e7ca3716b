// What a phone's page lays out differently, and a notice that leaves the floor. Sent to each page at
// connect (sandbox/app/web/gate.py); sandbox/app/web/page_layout.py says why, fills in each setting (a $ and a
// name) and holds CLIENT, the table of what this relies on in viser's client: its markup, and VISER below.
(() => {
  if (window.__phototaxisLayout) return;  // a page that reconnects keeps one observer
  window.__phototaxisLayout = true;
  // viser's phone layout (its breakpoint), its software-rendering notice's title, its bottom sheet's place,
  // and how long its sheet and a folder take to open (ms).
  const VISER = {narrow: $narrow, notice: $notice, sheet: {position: "fixed", bottom: "0px"}, openMs: 350};
  const NARROW = window.matchMedia(VISER.narrow), TOUCH = window.matchMedia($touch);
  const PRESS_PLAY = $press, TAP_PLAY = $tap;
  const NOTICE = VISER.notice, NOTICE_MS = $notice_ms;
  const LAMP = $lamp, CHALLENGE = $challenge, START = $start, BAR = $bar;
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
    (p) => p.style.position === VISER.sheet.position && p.style.bottom === VISER.sheet.bottom);
  const handleOf = (paper) => paper.querySelector("div[style*='cursor: pointer']");
  const sheetOpen = (paper) => paper.getBoundingClientRect().height > 1.5 * handleOf(paper).getBoundingClientRect().height;
  const makeDrawer = () => {
    const paper = sheet();
    if (!paper || drawers.has(paper) || !handleOf(paper)) return;
    drawers.add(paper);
    paper.style.width = "100%";
    // Open, it ends where the arena begins: a phone frames the arena as wide as the page at its top
    // (sandbox.app.view.scene.top_down_camera), so the floor's square is 100vw tall. viser's sheet took 60 %.
    paper.style.maxHeight = "max(40vh, calc(100vh - 100vw - 4px))";
    for (const box of paper.querySelectorAll("div[style*='width: 20em']")) box.style.width = "100%";  // its contents
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
      setTimeout(() => title.scrollIntoView({block: "start", behavior: "smooth"}), VISER.openMs);
    }, VISER.openMs);
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

  // A notice as tall as its text (Mantine holds each at 200 px, its overflow hidden: the "Goal changed" of
  // an F cut 242 px of text at top and bottom), up to the window's height, then a scroll bar of its own.
  const notices = document.createElement("style");
  notices.textContent = ".mantine-Notification-root { max-height: calc(100vh - 2em) !important;" +
    " overflow-y: auto !important; }";
  document.head.appendChild(notices);

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
})();
