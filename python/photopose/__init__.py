"""photopose: camera poses from the collinearity equations.

The C++ library's objects and calls (docs/python.md): camera models, rotation conventions and the
collinearity projection; robust single-image and batch resection; the Block (from numpy arrays,
the tables, COLMAP, BAL and Bundler); the weighted bundle adjustment with its statistics; the
table readers and writers. A failed Status of the library raises photopose.Error (a ValueError)
with the library's message.

Conventions: lengths in metres in the ground frame, angles in radians unless a name says deg;
R_camera_from_ground = Rx(omega) Ry(phi) Rz(kappa) ('rxryrz', the seed convention) maps ground to
the camera frame (u, v, w), w towards the viewer; 'opk' and 'pok' are converted at the boundaries.
Pixel marks are (Column, Row) with (0, 0) the top-left corner of the image, Row down.
"""

from ._photopose import *  # noqa: F401,F403  (the extension module is the API)
from ._photopose import Error, __version__  # noqa: F401
