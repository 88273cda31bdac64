"""The double-DQN update of every member of a stacked dueling network in one compiled call.

For networks this small (``in → 64 → 64``, heads of 32) an update is about three million
multiply-adds per member: what cost was the number of calls (autograd records some sixty nodes
an update, each a tensor operation of a few microseconds), not the arithmetic. Here one numba
kernel holds a member's whole update: the online network's forward pass on ``s`` and ``s'``
together, the target network's on ``s'``, the double-DQN target, the importance-weighted Huber
loss, and the backward pass written out by the chain rule, its matrix products by BLAS
(``np.dot``), everything else in plain loops. It loops over the members, so a member's update
never depends on how many are stacked beside it or where it sits. Adam then steps on the flat
gradient buffer the kernel wrote (:class:`~pursuit_bench.agents.adam.FlatAdam`). In training,
:func:`replay_update_kernel` makes a learner's whole update one call: the replay's batch, this
update, the Adam step and the new priorities.

The parameters are read from the flat buffers the learner keeps
(:func:`~pursuit_bench.agents.adam.flatten_parameters`):
parameter ``i`` of member ``m`` is the block ``offsets[i] + m · size_i`` of ``size_i`` numbers,
row-major ``(in, out)`` as :class:`~pursuit_bench.agents.network.StackedLinear` holds it.

The arithmetic is autograd's, in another order: losses and gradients equal
``loss(learner, batch).sum().backward()`` of ``tests/reference/dqn_loss.py`` to float rounding, not bit for bit
(``tests/test_fused.py``); docs/departures.md says so.
"""

from __future__ import annotations

import functools
from pathlib import Path

import numba
import numpy as np
import scipy.linalg.cython_blas  # noqa: F401  (the BLAS numba's np.dot calls: loaded, so that it can be limited)
from threadpoolctl import ThreadpoolController

from pursuit_bench.agents.adam import adam_step_kernel
from pursuit_bench.agents.network import HEAD, TRUNK
from pursuit_bench.agents.replay import draws_kernel, sample_kernel, update_priorities_kernel


@functools.cache
def one_thread_for_scipys_blas() -> None:
    """SciPy's OpenBLAS, which numba's np.dot calls, would split even these small products over
    every core: on a busy machine the threads wait on each other (measured: a member-update
    1.5-2x slower with two threads than with one). Training runs one process per core, so SciPy's
    BLAS gets one thread in this process; numpy's own BLAS (a library of its own) is left alone.

    Called by the learner (``DQNLearner``) as it is made, once per process: importing this module
    changes nothing of the process's threads."""
    controller = ThreadpoolController()
    scipys = [lib.filepath for lib in controller.lib_controllers if "scipy" in Path(lib.filepath).parent.name]
    if scipys:
        controller.select(filepath=scipys).limit(limits=1)


@numba.njit(cache=True, error_model="numpy")
def _weights(flat, offsets, member, n_in, n_actions):
    """Member ``member``'s twelve parameters as (in, out) and (out,) views of ``flat``."""
    shapes = ((n_in, TRUNK[0]), (TRUNK[0], TRUNK[1]), (TRUNK[1], HEAD), (HEAD, 1), (TRUNK[1], HEAD), (HEAD, n_actions))
    w1 = flat[offsets[0] + member * shapes[0][0] * shapes[0][1] :][: shapes[0][0] * shapes[0][1]]
    b1 = flat[offsets[1] + member * shapes[0][1] :][: shapes[0][1]]
    w2 = flat[offsets[2] + member * shapes[1][0] * shapes[1][1] :][: shapes[1][0] * shapes[1][1]]
    b2 = flat[offsets[3] + member * shapes[1][1] :][: shapes[1][1]]
    wv1 = flat[offsets[4] + member * shapes[2][0] * shapes[2][1] :][: shapes[2][0] * shapes[2][1]]
    bv1 = flat[offsets[5] + member * shapes[2][1] :][: shapes[2][1]]
    wv2 = flat[offsets[6] + member * shapes[3][0] :][: shapes[3][0]]
    bv2 = flat[offsets[7] + member :][:1]
    wa1 = flat[offsets[8] + member * shapes[4][0] * shapes[4][1] :][: shapes[4][0] * shapes[4][1]]
    ba1 = flat[offsets[9] + member * shapes[4][1] :][: shapes[4][1]]
    wa2 = flat[offsets[10] + member * shapes[5][0] * shapes[5][1] :][: shapes[5][0] * shapes[5][1]]
    ba2 = flat[offsets[11] + member * shapes[5][1] :][: shapes[5][1]]
    return (
        w1.reshape(shapes[0]),
        b1,
        w2.reshape(shapes[1]),
        b2,
        wv1.reshape(shapes[2]),
        bv1,
        wv2,
        bv2,
        wa1.reshape(shapes[4]),
        ba1,
        wa2.reshape(shapes[5]),
        ba2,
    )


@numba.njit(cache=True, error_model="numpy")
def network_inputs(obs, wall):
    """What the network sees of observations (B, n_obs): a contiguous copy, with the wall features
    ``(u, v)`` appended when ``wall`` (:func:`pursuit_bench.agents.dqn.wall_features`)."""
    rows, n_obs = obs.shape
    out = np.empty((rows, n_obs + (2 if wall else 0)), dtype=np.float32)
    _fill_inputs(obs, wall, out)
    return out


@numba.njit(cache=True, error_model="numpy")
def _fill_inputs(obs, wall, out):
    """:func:`network_inputs` written into ``out`` (B, n_obs [+ 2])."""
    rows, n_obs = obs.shape
    out[:, :n_obs] = obs
    if wall:
        for i in range(rows):
            x, y = obs[i, 0], obs[i, 1]
            dx, dy = obs[i, 4] - x, obs[i, 5] - y
            norm = np.sqrt(dx * dx + dy * dy)
            scale = max(norm, np.float32(1e-12))  # torch's clamp_min
            lx, ly = (dx / scale, dy / scale) if norm > 0 else (np.float32(1.0), np.float32(0.0))
            out[i, n_obs] = x * lx + y * ly
            out[i, n_obs + 1] = y * lx - x * ly


@numba.njit(cache=True, error_model="numpy")
def dense_relu(x, w, b):
    """``relu(x @ w + b)``."""
    out = np.empty((x.shape[0], w.shape[1]), dtype=np.float32)
    _dense_relu_into(x, w, b, out)
    return out


@numba.njit(cache=True, error_model="numpy")
def _dense_relu_into(x, w, b, out):
    """``relu(x @ w + b)`` written into ``out`` (BLAS writes the product there)."""
    np.dot(x, w, out)
    for i in range(out.shape[0]):
        for j in range(out.shape[1]):
            value = out[i, j] + b[j]
            out[i, j] = value if value > 0 else np.float32(0.0)


@numba.njit(cache=True, error_model="numpy")
def _layers(rows, n_actions):
    """Room for one member's forward pass of ``rows`` inputs: the hidden layers h1, h2, hv, ha,
    the advantages, the Q-values and V(s); made once per call and used by member after member
    (fresh arrays for every member and layer cost more than their arithmetic)."""
    return (
        np.empty((rows, TRUNK[0]), dtype=np.float32),
        np.empty((rows, TRUNK[1]), dtype=np.float32),
        np.empty((rows, HEAD), dtype=np.float32),
        np.empty((rows, HEAD), dtype=np.float32),
        np.empty((rows, n_actions), dtype=np.float32),
        np.empty((rows, n_actions), dtype=np.float32),
        np.empty(rows, dtype=np.float32),
    )


@numba.njit(cache=True, error_model="numpy")
def _forward(x, p, layers):
    """One member's forward pass for inputs x (B, in) into ``layers`` (:func:`_layers` of B
    rows): the hidden layers, the advantages, the Q-values (B, A) and V(s) (B,)."""
    w1, b1, w2, b2, wv1, bv1, wv2, bv2, wa1, ba1, wa2, ba2 = p
    h1, h2, hv, ha, advantage, q, value = layers
    _dense_relu_into(x, w1, b1, h1)
    _dense_relu_into(h1, w2, b2, h2)
    _dense_relu_into(h2, wv1, bv1, hv)
    _dense_relu_into(h2, wa1, ba1, ha)
    np.dot(ha, wa2, advantage)
    rows, n_actions = advantage.shape
    for i in range(rows):
        v = bv2[0]
        for k in range(hv.shape[1]):
            v += hv[i, k] * wv2[k]
        value[i] = v
        mean = np.float32(0.0)
        for j in range(n_actions):
            advantage[i, j] += ba2[j]
            mean += advantage[i, j]
        mean /= np.float32(n_actions)
        for j in range(n_actions):
            q[i, j] = v + advantage[i, j] - mean


@numba.njit(cache=True, error_model="numpy")
def q_and_value_kernel(flat, offsets, n_actions, obs, wall, first=0):
    """Q-values (M, B, A) and V(s) (M, B) of members ``first …`` for observations (M, B, n_obs)."""
    members, rows, n_obs = obs.shape
    n_in = n_obs + (2 if wall else 0)
    q = np.empty((members, rows, n_actions), dtype=np.float32)
    value = np.empty((members, rows), dtype=np.float32)
    inputs = np.empty((rows, n_in), dtype=np.float32)
    layers = _layers(rows, n_actions)
    for m in range(members):
        p = _weights(flat, offsets, first + m, n_in, n_actions)
        _fill_inputs(obs[m], wall, inputs)
        _forward(inputs, p, layers)
        q[m] = layers[5]
        value[m] = layers[6]
    return q, value


@numba.njit(cache=True, error_model="numpy")
def undecided_kernel(q, value, gap):
    """Which rows (B,) of Q-values (B, A) and V(s) (B,), both float32, have their two best
    actions within ``gap`` (a float32) times the row's decision scale, 1 + |V| + max |Q − V|
    (``agents.dqn.decision_scale``): the numpy expression ``top2 − top1 <= gap · scale`` row by
    row, in float32 as numpy computes it (one action: never undecided)."""
    rows, actions = q.shape
    out = np.zeros(rows, dtype=np.bool_)
    one = np.float32(1.0)
    for i in range(rows):
        best = q[i, 0]
        second = -np.inf
        for a in range(1, actions):
            x = q[i, a]
            if x > best:
                second = best
                best = x
            elif x > second:
                second = x
        v = value[i]
        deviation = np.float32(0.0)
        for a in range(actions):
            deviation = max(deviation, abs(q[i, a] - v))
        scale = one + abs(v) + deviation
        out[i] = actions > 1 and np.float32(best - second) <= gap * scale
    return out


@numba.njit(cache=True, error_model="numpy")
def choose_kernel(q, uniforms, randoms, epsilon):
    """Actions (M, B) from Q-values (M, B, A): each row's first largest Q, or where
    ``uniforms[m, b] < epsilon`` the action ``randoms[m, b]`` (ε-greedy: the draws come from the
    members' generators, made by the caller; ``uniforms`` of width 0 for greedy choices)."""
    members, rows, n_actions = q.shape
    explore = uniforms.shape[1] > 0
    choices = np.empty((members, rows), dtype=np.int64)
    for m in range(members):
        for i in range(rows):
            best = 0
            for j in range(1, n_actions):
                if q[m, i, j] > q[m, i, best]:
                    best = j
            choices[m, i] = randoms[m, i] if explore and uniforms[m, i] < epsilon else best
    return choices


@numba.njit(cache=True)
def exploration_kernel(generators, rows, n_actions):
    """The draws of ε-greedy for ``rows`` choices per member, from the members' generators (a
    typed list, :mod:`~pursuit_bench.agents.generators`): member m's ``rows`` uniforms, then its
    ``rows`` random actions, both from ``generators[m]``; (M, rows) each."""
    members = len(generators)
    uniforms = np.empty((members, rows))
    randoms = np.empty((members, rows), dtype=np.int64)
    for m in range(members):
        uniforms[m] = generators[m].random(rows)
        randoms[m] = generators[m].integers(0, n_actions, rows)
    return uniforms, randoms


@numba.njit(cache=True, error_model="numpy")
def act_kernel(flat, offsets, n_actions, obs, wall, generators, epsilon):
    """:func:`q_and_value_kernel` for every member, then :func:`choose_kernel` ε-greedy on the
    draws of :func:`exploration_kernel`: the actions (M, B), Q-values (M, B, A) and V(s) (M, B)
    of one acting step."""
    q, value = q_and_value_kernel(flat, offsets, n_actions, obs, wall)
    uniforms, randoms = exploration_kernel(generators, obs.shape[1], n_actions)
    return choose_kernel(q, uniforms, randoms, epsilon), q, value


@numba.njit(cache=True, error_model="numpy")
def _backward_dense(x, grad_out, w, grad_w, grad_b, grad_in):
    """Write ``x.T @ grad_out`` into grad_w, the column sums into grad_b and the input's gradient
    ``grad_out @ w.T`` into grad_in (BLAS writes each product where it belongs: no copies)."""
    np.dot(x.T, grad_out, grad_w)
    _column_sums(grad_out, grad_b)
    np.dot(grad_out, w.T, grad_in)


@numba.njit(cache=True, error_model="numpy")
def _column_sums(x, out):
    """``out[j] = x[0, j] + x[1, j] + …`` in that order, row by row (so that the columns add in
    vector lanes side by side, each in the order of a plain loop down the column)."""
    out[:] = np.float32(0.0)
    for i in range(x.shape[0]):
        for j in range(x.shape[1]):
            out[j] += x[i, j]


@numba.njit(cache=True, error_model="numpy")
def update_kernel(
    online, target, grad, offsets, n_actions, obs, next_obs, actions, rewards, terminated, weights, gamma, delta, wall
):
    """One double-DQN step's loss and gradient for every member: writes the gradient of the sum
    of the members' losses into ``grad`` (the flat layout of ``online``) and returns the losses
    (M,) and TD errors ``Q(s, a) - y`` (M, B). Observations (M, B, n_obs) as the replay holds
    them: ``wall`` appends the wall features."""
    members, rows, n_obs = obs.shape
    n_in = n_obs + (2 if wall else 0)
    losses = np.empty(members, dtype=np.float32)
    td = np.empty((members, rows), dtype=np.float32)
    both = np.empty((2 * rows, n_in), dtype=np.float32)
    online_layers, target_layers = _layers(2 * rows, n_actions), _layers(rows, n_actions)
    # the backward pass's arrays, made once and used by member after member
    grad_q = np.empty((rows, n_actions), dtype=np.float32)
    grad_value = np.empty(rows, dtype=np.float32)
    grad_hv, grad_ha = np.empty((rows, HEAD), dtype=np.float32), np.empty((rows, HEAD), dtype=np.float32)
    grad_h2, grad_h2_value = np.empty((rows, TRUNK[1]), dtype=np.float32), np.empty((rows, TRUNK[1]), dtype=np.float32)
    grad_h1 = np.empty((rows, TRUNK[0]), dtype=np.float32)
    for m in range(members):
        p = _weights(online, offsets, m, n_in, n_actions)
        g = _weights(grad, offsets, m, n_in, n_actions)
        _fill_inputs(obs[m], wall, both[:rows])
        _fill_inputs(next_obs[m], wall, both[rows:])
        _forward(both, p, online_layers)
        h1, h2, hv, ha, _, q, _ = online_layers
        _forward(both[rows:], _weights(target, offsets, m, n_in, n_actions), target_layers)
        q_target = target_layers[5]
        grad_q[:] = np.float32(0.0)
        total = np.float32(0.0)
        for i in range(rows):
            best = 0
            for j in range(1, n_actions):
                if q[rows + i, j] > q[rows + i, best]:
                    best = j
            y = rewards[m, i] + np.float32(gamma) * (np.float32(1.0) - terminated[m, i]) * q_target[i, best]
            error = q[i, actions[m, i]] - y
            td[m, i] = error
            size = abs(error)
            if size < delta:
                huber = np.float32(0.5) * error * error
            else:
                huber = np.float32(delta) * (size - np.float32(0.5 * delta))
            total += weights[m, i] * huber
            clipped = min(max(error, np.float32(-delta)), np.float32(delta))
            grad_q[i, actions[m, i]] = weights[m, i] / np.float32(rows) * clipped
        losses[m] = total / np.float32(rows)
        # Q = V + A - mean(A): dV = Σ_a dQ, dA = dQ - Σ_a dQ / A
        grad_advantage = grad_q
        for i in range(rows):
            summed = np.float32(0.0)
            for j in range(n_actions):
                summed += grad_q[i, j]
            grad_value[i] = summed
            for j in range(n_actions):
                grad_advantage[i, j] -= summed / np.float32(n_actions)
        _, _, w2, _, wv1, _, wv2, _, wa1, _, wa2, _ = p
        gw1, gb1, gw2, gb2, gwv1, gbv1, gwv2, gbv2, gwa1, gba1, gwa2, gba2 = g
        ha_s, hv_s, h2_s, h1_s = ha[:rows], hv[:rows], h2[:rows], h1[:rows]
        _backward_dense(ha_s, grad_advantage, wa2, gwa2, gba2, grad_ha)
        # the value head's one output: dw = hv.T @ dV, dhv = dV wv2
        gbv2[0] = np.float32(0.0)
        for k in range(HEAD):
            gwv2[k] = np.float32(0.0)
        for i in range(rows):
            gbv2[0] += grad_value[i]
            for k in range(HEAD):
                gwv2[k] += hv_s[i, k] * grad_value[i]
                grad_hv[i, k] = grad_value[i] * wv2[k] if hv_s[i, k] > 0 else np.float32(0.0)
        for i in range(rows):
            for k in range(HEAD):
                if ha_s[i, k] <= 0:
                    grad_ha[i, k] = np.float32(0.0)
        _backward_dense(h2_s, grad_ha, wa1, gwa1, gba1, grad_h2)
        _backward_dense(h2_s, grad_hv, wv1, gwv1, gbv1, grad_h2_value)
        grad_h2 += grad_h2_value  # the two streams' sum
        for i in range(rows):
            for k in range(TRUNK[1]):
                if h2_s[i, k] <= 0:
                    grad_h2[i, k] = np.float32(0.0)
        _backward_dense(h1_s, grad_h2, w2, gw2, gb2, grad_h1)
        for i in range(rows):
            for k in range(TRUNK[0]):
                if h1_s[i, k] <= 0:
                    grad_h1[i, k] = np.float32(0.0)
        np.dot(both[:rows].T, grad_h1, gw1)
        _column_sums(grad_h1, gb1)
    return losses, td


@numba.njit(cache=True, error_model="numpy")
def replay_update_kernel(
    replay, generators, batch_size, beta, online, target, grad, offsets, n_actions, gamma, delta, wall, adam
):
    """One whole update of every member, in one call: the members' uniforms
    (:func:`~pursuit_bench.agents.replay.draws_kernel`, from ``generators``, a typed list), the
    batch drawn from the replay (:func:`~pursuit_bench.agents.replay.sample_kernel`), the loss
    and gradient (:func:`update_kernel`), the Adam step
    (:func:`~pursuit_bench.agents.adam.adam_step_kernel`, ``adam`` its buffers and scalars) and
    the new priorities: the same calls, in the same order, as ``sample``, ``learn`` and
    ``update_priorities`` made one by one, so the same numbers. ``replay`` is
    :meth:`ReplayStack.arrays`' tuple, and must hold transitions. Returns the losses (M,); a
    ValueError, as ``learn``'s, if a drawn action lies outside ``0 … n_actions - 1`` (nothing but
    the generators has then moved on).

    numba's cache checks this file only: after editing the kernels it calls in ``replay.py`` or
    ``adam.py``, touch this file (or clear the cache); until then ``tests/test_dqn.py``'s
    comparison with the calls made one by one fails on any change of their numbers."""
    (
        tree,
        leaves,
        size,
        alpha,
        epsilon,
        prioritized,
        obs,
        actions,
        rewards,
        next_obs,
        terminated,
        priorities,
        max_priority,
    ) = replay
    fractions, uniform = draws_kernel(generators, batch_size, size, prioritized)
    indices, weights, b_obs, b_actions, b_rewards, b_next, b_terminated = sample_kernel(
        tree, leaves, size, beta, fractions, uniform, obs, actions, rewards, next_obs, terminated
    )
    for action in b_actions.ravel():
        if not 0 <= action < n_actions:
            raise ValueError("stored actions: expected values in [0, n_actions) of this learner")
    losses, td = update_kernel(
        online,
        target,
        grad,
        offsets,
        n_actions,
        b_obs,
        b_next,
        b_actions,
        b_rewards,
        b_terminated,
        weights,
        gamma,
        delta,
        wall,
    )
    adam_step_kernel(*adam)
    if prioritized:
        update_priorities_kernel(priorities, tree, leaves, alpha, epsilon, max_priority, indices, td)
    return losses
