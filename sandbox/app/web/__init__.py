"""The server's transport and who may talk to it. A page's message passes the gate (Host, Origin,
token), is decoded and checked (:mod:`.well_formed`), budgeted (:mod:`.rates`) and read by the inbox
before viser acts on it; every viser callback then runs on the app's one event queue (:mod:`.events`).
viser's event loop runs the checks; the app's event thread runs everything else.

- :mod:`.gate`        the viser server with the gate: :func:`~.gate.start_server`
- :mod:`.access`      who may connect, from each request alone (Host, Origin, token)
- :mod:`.well_formed` the messages a page may send, decoded and checked in one pass
- :mod:`.rates`       how much each page may send, per connection
- :mod:`.refusals`    refusals in the log, at most a line a second per page
- :mod:`.inbox`       every message checked before viser acts on it
- :mod:`.events`      the one event queue every change of the app's state runs on
- :mod:`.viser_seam`  the one place that names viser's private code, with its table and check
- :mod:`.icons`, :mod:`.wakeups`, :mod:`.memory`  viser's icons, buffers woken from threads, memory freed
- :mod:`.pacing`      what each viewer is sent, at the rate it draws
- :mod:`.stopping`    how ``serve`` stops (SIGTERM as Ctrl+C)
- :mod:`.page_keys`, :mod:`.page_layout`, :mod:`.page_open`, :mod:`.page_sends`, :mod:`.page_touch`
  the scripts the page runs in viser's client (``page/*.js``), each with the table of what it relies on there
- :mod:`.client_seam` the scripts as sent, and the check of their tables against viser's client
"""
