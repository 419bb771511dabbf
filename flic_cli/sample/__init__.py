"""A deterministic synthetic street and an HDL-64E-like ray caster: the embedded sample dataset.

The project ships no real lidar data (the Moosmann logs may not be redistributed, SemanticKITTI is a
large download). When the user gives no data path, the CLI writes this package's sample once into a
per-user cache folder and runs on it, so the main command of the README works out of the box.

Modules
-------
- :mod:`~flic_cli.sample.scene`: the primitives (:class:`Box`, :class:`Cylinder`, :class:`Ground`),
  :class:`Scene`, and :func:`custom_scene`, :func:`person`, :func:`car` for targeted scenes;
- :mod:`~flic_cli.sample.street`: the street generator, :func:`make_scene`;
- :mod:`~flic_cli.sample.sensor`: the HDL-64E model and the ray caster :func:`cast` (noise,
  dropouts, the recording car :data:`EGO_VEHICLE`), and the other sensors' profiles
  :data:`SENSOR_PROFILES` (``flic sample --sensor``: VLP-16, VLP-32C, HDL-32E, OS1-64, OS1-128,
  OS2-128 beam tables and columns);
- :mod:`~flic_cli.sample.render`: :func:`render_kitti` (a scan in scan order with labels) and
  :func:`render_moosmann` (a range image with per-pixel truth);
- :mod:`~flic_cli.sample.writer`: :func:`write_sample`, :func:`ensure_sample` (both formats, written
  through :mod:`flic_cli.io`).

Targeted scenes for tests
-------------------------
Everything is in the sensor frame (x forward, y left, z up, metres; the sensor level at the origin,
:data:`SENSOR_HEIGHT_M` above the road). Without ``noise=True`` the renderers are exact: every ray
whose first hit lies within :data:`MAX_RANGE_M` returns its true range. Two people 1 m apart on the
sidewalk right of a 4 m-wide road that rises by 2 deg, and a car 20 m ahead::

    import numpy as np
    from flic_cli.sample import Ground, car, custom_scene, person, render_kitti, render_moosmann

    street = Ground(slope=np.tan(np.radians(2.0)), road_y=(-2.0, 2.0), sidewalk_y=(-5.0, 5.0))
    scene = custom_scene(
        person(8.0, -3.0, instance=1, ground=street),
        person(9.0, -3.0, instance=2, ground=street),
        car(20.0, 0.0, instance=3, ground=street),
        ground=street,                          # default: flat road everywhere (Ground.flat())
    )
    points, labels = render_kitti(scene)        # (N, 4) float32 in scan order, (N,) uint32
    image, semantic, instance = render_moosmann(scene)   # RangeImage (64 x 870) + truth

``scene.seen_from(x, y)`` moves the sensor; any :class:`Box` or :class:`Cylinder` (with a class id
from :mod:`flic_cli.classes` and an instance id for things) can be passed to :func:`custom_scene`,
and ``Scene(0, 0, np.eye(3, 4), None, boxes, cylinders)`` has no ground at all.

The street
----------
One straight one-way street per seed, in a world frame equal to the sensor frame of frame 0 (x
forward along the street, y left, z up, metres). The ego car drives down its single 3.8-4.2 m lane
at 10 m/s (1 m per frame at 10 Hz) and its sensor sits :data:`SENSOR_HEIGHT_M` above the road. The
road rises ahead with a gentle slope (1-2 deg: ``z = -1.73 + slope * x`` in the sensor frame); a
0.12 m kerb steps up to the sidewalks. Along the street:

- both parking strips are lined with parked cars, some bumper to bumper, most 1-2.5 m apart, now
  and then a 3.5-7 m driveway, and sometimes a van or truck on the left;
- on the right, a 3.4-4 m sidewalk with a cycle track along the kerb and shops: street trees
  (trunk + crown) every 4-7 m and, 1-3 m apart, lamps, sign posts, bollards, bins, planters,
  bicycles, scooters, utility cabinets and advertising columns along the kerb, benches, cafe tables
  and planters along the shop windows, and most of the 40-70 pedestrians (some in groups);
- on the left, a 2.2-2.8 m sidewalk with trees and sparser furniture, and front gardens (terrain)
  with hedges, fences and low walls in segments with gaps, shrubs and small trees;
- buildings in blocks of 1-4 segments whose frontage steps back and forth by 1-2 m, with 1.6-4.5 m
  alleys between blocks (through some, a building set further back); a building closes each end
  of the street;
- traffic: a car 6-9 m ahead keeping its distance to the ego car (often a second one ahead of it
  and one following the ego car) and 2-5 cyclists on the cycle track.

Every primitive is an axis-aligned or yaw-rotated box or a vertical cylinder with a SemanticKITTI
raw class id and, for things, an instance id (0 for stuff). A car is a body box, a thin roof slab
and six window pillars: rays pass through its windows and see what lies beyond, so its roof is
separated from its body by a gap of a few rows except at the pillars. Facades have glazed windows
(shops: glazed from the pavement up between narrow pillars); a ray through a window returns from
the room behind it, at a depth fixed per window, or not at all.

The sensor
----------
:data:`HDL64_PITCH_DEG` models the Velodyne HDL-64E's two laser blocks; :func:`cast` intersects a
grid of rays (beam pitches x column azimuths) with the scene (first hit, vectorised over rays) and
adds range noise, random dropouts, dark-paint dropouts on some cars (growing with range), window
glass, and grazing-angle dropouts on the ground beyond 15 m (dark asphalt: 5 % of the returns left
at 27 m). Occlusions and moving objects come out of the geometry.

The Moosmann recording car hides its sensor's lower beams: :data:`EGO_VEHICLE` (a 4.5 x 1.8 m box
whose top lies 0.5 m below the sensor, from 2 m ahead of it to 2.5 m behind) swallows the beams
steeper than 14 deg looking ahead and 11 deg looking back, about 9,300 of the 55,680 pixels of a
frame; rays that hit it give no return (range 0). Sideways even the lowest beam clears it. The
SemanticKITTI sequence is cast without it, like the real KITTI scans, which lose only a few
returns of their lowest beams behind the car: about 20 % of its points are ground.

Realism of the Moosmann log
---------------------------
Real Moosmann frames hold 40k-48k valid pixels of 870 x 64, 37k-43k of them left after ground
removal, and FLIC finds about 90-130 clusters in them. The default sample (seed 0, 20 frames) has
43.5k-44.1k valid pixels, 36.7k-39.8k (mean 38.3k) left after the paper's ground removal
(:func:`flic_cli.ground.paper_ground`), and FLIC with 0 Map Connections and the paper's ground
removal finds 41-58 clusters of at least 100 pixels (mean 47); seeds 1-3 give 34.8k-40.3k
non-ground pixels and 38-62 clusters. The cluster count falls short of the real logs': in an
870 x 64 image an object beyond about 15 m covers fewer than 100 pixels, and nearer objects hide one
another along the street, so adding objects (more furniture, trees, pedestrians, open space between
the parked cars) does not raise it beyond about 50-60. The KITTI scans hold about 124k points each.

Outputs
-------
:func:`write_sample` writes the same frames both as a SemanticKITTI sequence (points in the
sensor's scan order, so that :func:`flic_cli.projection.project_points` recovers the 64 rings) and
as a Moosmann-style log (870 x 64 16-bit PNG range images + ``img.cfg``), into a temporary folder
renamed into place once complete. :func:`ensure_sample` writes the default sample into
:func:`default_sample_dir` once and reuses it afterwards.

Other sensors
-------------
``write_sample(out, sensor="vlp16")`` (``flic sample OUT --sensor vlp16``) casts the same frames
with another sensor's beam table and columns (:data:`SENSOR_PROFILES`: ``vlp16``, ``vlp32c``,
``hdl32e``, ``hdl64e`` (the default), ``os1-64``, ``os1-128``, ``os2-128``; where each table comes
from is in its :attr:`SensorProfile.source`), as the SemanticKITTI sequence alone, with
``out/sensor.toml`` beside it: the ``[projection]`` table (rows = beams, width = columns) with
which ``flic ... --config out/sensor.toml`` reads the sequence, and in a comment the Bridge
parameters that follow the beam gap (:func:`flic_cli.sensor_params.bridge_parameters`), which
every run derives from the data's rows itself (:func:`flic_cli.sensor_params.for_dataset`). The
default profile writes exactly the sample described above.
"""

from __future__ import annotations

from flic_cli.sample.render import MoosmannRender, render_kitti, render_moosmann
from flic_cli.sample.scene import (
    SENSOR_HEIGHT_M,
    Box,
    Cylinder,
    Ground,
    Scene,
    car,
    custom_scene,
    person,
)
from flic_cli.sample.sensor import (
    DEFAULT_SENSOR,
    EGO_VEHICLE,
    HDL64_PITCH_DEG,
    MAX_RANGE_M,
    MOOSMANN_HEIGHT,
    MOOSMANN_WIDTH,
    SENSOR_PROFILES,
    SensorProfile,
    cast,
    kitti_azimuths,
    moosmann_azimuths,
)
from flic_cli.sample.street import make_scene
from flic_cli.sample.writer import SamplePaths, default_sample_dir, ensure_sample, write_sample

__all__ = [
    "DEFAULT_SENSOR",
    "EGO_VEHICLE",
    "HDL64_PITCH_DEG",
    "MAX_RANGE_M",
    "MOOSMANN_HEIGHT",
    "MOOSMANN_WIDTH",
    "SENSOR_HEIGHT_M",
    "Box",
    "Cylinder",
    "Ground",
    "MoosmannRender",
    "SENSOR_PROFILES",
    "SamplePaths",
    "Scene",
    "SensorProfile",
    "car",
    "cast",
    "custom_scene",
    "default_sample_dir",
    "ensure_sample",
    "kitti_azimuths",
    "make_scene",
    "moosmann_azimuths",
    "person",
    "render_kitti",
    "render_moosmann",
    "write_sample",
]
