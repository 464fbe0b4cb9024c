"""The detector packs whose measured drops the studies' drop models were fitted on."""

#: The lss-R1 pack rigopt shipped until the stronger detector replaced it (studies/stronger_detector); git keeps its
#: weights at that commit.
PREVIOUS_R1_PACK = "the lss-R1 models shipped until commit c16e580 (own mAP 0.223-0.237 on R1's test scenes)"
