"""flic: Fast Lidar Image Clustering and its peers, as a command-line tool and a Python API.

Layout (one job per module; where a new format, method or ground remover goes: one file in its
package plus one line in :mod:`flic_cli.registry`):

- ``flic_cli.registry``     the extension points by name: dataset formats, methods, removers
- ``flic_cli.io``           the data formats (SemanticKITTI, Moosmann logs), predictions, atomic
  writes, PLY export; ``io.base`` is the ``Dataset`` / ``Frame`` / ``FrameRef`` interface
- ``flic_cli.labels``       the SemanticKITTI label encoding (semantic / instance bits)
- ``flic_cli.classes``      SemanticKITTI's classes (things, ground, training classes)
- ``flic_cli.semantics``    semantic classes in panoptic predictions (``--semantics``)
- ``flic_cli.component``    what a configurable component is (a validated frozen dataclass)
- ``flic_cli.config``       config files (presets in ``config/presets/``) into a typed ``Config``
- ``flic_cli.range_image``  the range image every image method works on
- ``flic_cli.projection``   points to range image (ring recovery, spherical projection)
- ``flic_cli.ground``       ground removers (paper, Bogoslavskyi & Stachniss, column,
  Patchwork++)
- ``flic_cli.methods``      the clusterers (FLIC with Map Connections, Bogoslavskyi, DBSCAN,
  Bridge) and their connected-component engine
- ``flic_cli.metrics``      the evaluation protocol (IoU, P_x, over/under-segmentation, panoptic
  quality, ground scores, bootstrap intervals)
- ``flic_cli.runs``         segment / evaluate / benchmark / sweep-threshold (``runs.spec``: the
  typed run specifications), parallel frame loops, resumable stores, tables
- ``flic_cli.sample``       the built-in synthetic street and ray caster (data without download)
- ``flic_cli.plots``        the PNG figures
- ``flic_cli.api``          the Python API (segment points or a range image)
- ``flic_cli.cli``          the Typer command line
"""

__version__ = "0.1.0"
