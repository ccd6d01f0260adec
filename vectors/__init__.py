"""Golden packet vectors: fixed frames and fixed exchanges, with the code that makes and checks
them (docs/vectors.md).

The data files beside this module are the committed set (`mavconform vectors generate`
rewrites them byte for byte). The modules, by what they hold:
- dialect_info  which messages get vectors (every message the dialect XML defines) and their layout
- fields        field values in the files, and when two decoders' values are the same
- messages      the message vectors, valid and deliberately broken; the published test key
- exchanges     the reference GCS against each vehicle profile, recorded (and the handover hook)
- store         the files on disk: write, read, check a regeneration
- schemas       the JSON Schemas of the two file formats (written to schema/)
- verify        a codec's results judged against the vectors; our codec's results
- deviations    known deviations of a codec (known_deviations.toml)
- replay        an exchange's GCS side sent to a target, and where its replies differ
"""
