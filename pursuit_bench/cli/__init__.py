"""The command line: ``pursuit-bench``."""
