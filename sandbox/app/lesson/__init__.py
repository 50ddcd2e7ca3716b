"""A class at once (``phototaxis serve --class``, issue 58): every student a world of their own, the
teacher's wall. Built on the main thread; runs on the app's event thread, as the panel does.

The fifth room, above the panel, the view, the world and the web (docs/code.md, "The app in rooms"):
``seats`` (who holds which world, the identities the server issues), ``pages`` (one page as the
server the panel and the view draw on), ``desk`` (a student's panel and floor on their page),
``classroom`` (the students' worlds, the projector, a scene sent, the class challenge) and ``wall``
(the teacher's Class folder).
"""
