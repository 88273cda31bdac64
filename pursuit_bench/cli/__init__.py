"""The command line: ``pursuit-bench``. The top layer: it may import every other one."""
