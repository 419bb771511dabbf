"""flic: Fast Lidar Image Clustering and its peers, as a command-line tool.

Layout (one job per module):

- ``flic_cli.io``         reading and writing formats (SemanticKITTI, Moosmann logs, predictions)
- ``flic_cli.range_image`` the range image shared by every image method (ring recovery, projection)
- ``flic_cli.ground``     ground extraction (paper, Bogoslavskyi & Stachniss, by label)
- ``flic_cli.methods``    the clusterers (FLIC with Map Connections, Bogoslavskyi, DBSCAN)
- ``flic_cli.metrics``    the evaluation protocol (IoU, P_x, over/under-segmentation)
- ``flic_cli.runs``       segment / evaluate / benchmark / sweep-threshold pipelines
- ``flic_cli.cli``        the Typer command line
"""

__version__ = "0.1.0"
