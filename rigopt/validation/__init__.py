"""The validation wing: what checks the metrics and the designer against measured transfer, apart from the core.

- ``synthetic``: the synthetic multi-rig benchmark rigopt renders itself (scenes, rendering, the nuScenes-layout
  dataset, mAP evaluation); numpy only.
- ``detectors``: the torch detectors trained on it (LSS- and PETR-style families, training, inference, the
  shipped R1 models); the only part of rigopt that imports torch (``pip install -e ".[bench]"``).
- ``designs``: a design measured with the shipped detectors beside its yardsticks (``rigopt validate``).

Inside the wing ``synthetic`` imports neither of the others and ``detectors`` not ``designs`` (tested).
"""
