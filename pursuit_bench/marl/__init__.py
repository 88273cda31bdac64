"""The field's multi-agent algorithms on pursuit-bench, through BenchMARL (the ``marl`` extra):
the ten conditions as BenchMARL tasks (``benchmarl_task.py``) and a run of one of its algorithms
that writes team files ``score`` plays (``train.py``; ``pursuit-bench marl train``)."""
