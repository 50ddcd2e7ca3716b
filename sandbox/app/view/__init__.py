"""What is drawn on the floor, from snapshots, on the app's event thread: the scene, the boxes as
hexagons, the legend, the colours shared with recordings, the shape being drawn, the compared world, and
Pillow frames for GIF and MP4.

- :mod:`.scene`    one viser node per kind of thing, updated from snapshots
- :mod:`.hexagons` the boxes drawn as hexagons
- :mod:`.legend`   the legend and the heat map's colour bar
- :mod:`.palette`  colours and picture-making shared with recordings and figures
- :mod:`.sketch`   the shape being drawn: outline, numbered handles, the preview of the goal
- :mod:`.partner`  compare mode's second world, drawn beside the running one
- :mod:`.floor`    where a click ray meets the floor
- :mod:`.frames`   Pillow pictures of a snapshot for GIF / MP4
"""
