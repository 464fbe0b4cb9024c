"""Code the studies share and the package does not use: tables written as CSV and markdown (``tables``), the
agreement of two transfer tables' drops (``agreement``) and a timestamped progress log (``logs``). A study script
puts ``studies/`` on its path (``sys.path``) and imports ``studylib.<module>``."""
