"""The torch detectors trained on the synthetic benchmark: LSS- and PETR-style families, training, inference,
the cross-rig protocol and the shipped R1 models."""
