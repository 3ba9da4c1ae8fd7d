"""``rtlab view``: the scene in a browser, rendered live by the core (issue 13).

camera.py is the mouse's and keyboard's maths (orbit, pan, zoom, walk); session.py renders a
view's frames, one at a time, merging the moves that arrive meanwhile; server.py is the web
server (tornado) that serves the page in static/ and the frames over a WebSocket; bench.py is
``rtlab bench viewer``.
"""
