// A folder of the panel opened on this page and brought into view (sandbox/app/web/page_open.py), through
// the layout script's window.__phototaxisOpenFolder (layout.js): nothing of viser's client of its own.
window.__phototaxisOpenFolder?.($title, [$inside]);
