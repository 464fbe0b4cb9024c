"""The synthetic multi-rig benchmark: scenes, the ray-cast renderer, the nuScenes-layout dataset, mAP (numpy)."""
