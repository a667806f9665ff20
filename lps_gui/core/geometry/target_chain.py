"""Initial mounting poses of the targets, from the views that see two at once (SPEC 13).

No layout is given: each view's PnP pose of each target it sees gives, for
every pair (a, b) seen together, one estimate of b's pose in a's frame. The
targets are chained from target 0 over a maximum spanning tree of the tie
counts (most shared views first, so the chain runs through the best-tied
pairs), each edge the chordal mean of its views' estimates. A target with no
chain to target 0 cannot be placed in the world frame: that is a one-line
error naming it and the views that saw it. The joint solver refines the result.
"""
from __future__ import annotations

import heapq

import numpy as np

from lps_gui.core.geometry.rotation import chordal_mean
from lps_gui.errors import DegenerateGeometryError


def tie_counts(ok: np.ndarray) -> np.ndarray:
    """(T, T) number of views that see both targets of a pair (diagonal: views that see the target)."""
    o = ok.astype(int)
    return o.T @ o


def _spanning_tree(ties: np.ndarray) -> dict[int, int]:
    """parent of every target reachable from target 0 over pairs with ties, maximum tie counts first."""
    parent = {0: -1}
    heap = [(-ties[0, b], 0, b) for b in range(1, len(ties)) if ties[0, b] > 0]
    heapq.heapify(heap)
    while heap:
        _, a, b = heapq.heappop(heap)
        if b in parent:
            continue
        parent[b] = a
        heap += [(-ties[b, c], b, c) for c in range(len(ties)) if c not in parent and ties[b, c] > 0]
        heapq.heapify(heap)
    return parent


def _relative(R: np.ndarray, t: np.ndarray, a: int, b: int, views: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Pose of target b in target a's frame (X_a = Q X_b + p), averaged over ``views``."""
    Ra, ta, Rb, tb = R[views, a], t[views, a], R[views, b], t[views, b]
    Q = np.einsum("kji,kjl->kil", Ra, Rb)  # Ra^T Rb
    p = np.einsum("kji,kj->ki", Ra, tb - ta)  # Ra^T (tb - ta)
    return chordal_mean(Q), p.mean(axis=0)


def chain_targets(
    R_cam_target: np.ndarray, t_cam_target: np.ndarray, ok: np.ndarray,
    target_ids: list[str], view_names: list[str],
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Every target's pose in target 0's frame: Q (T, 3, 3), p (T, 3) mm, and the tie counts (T, T).

    ``R_cam_target`` (K, T, 3, 3), ``t_cam_target`` (K, T, 3): each view's pose of each target
    (x_cam = R X + t), valid where ``ok`` (K, T).
    """
    T = len(target_ids)
    ties = tie_counts(ok)
    parent = _spanning_tree(ties)
    missing = [j for j in range(T) if j not in parent]
    if missing:
        j = missing[0]
        seen = [view_names[i] for i in np.flatnonzero(ok[:, j])]
        if not seen:
            raise DegenerateGeometryError(
                f"target {target_ids[j]} was not found in any view; check its marker ids and dictionary, "
                "or remove it from session.json targets")
        shown = ", ".join(seen[:5]) + (f" and {len(seen) - 5} more" if len(seen) > 5 else "")
        raise DegenerateGeometryError(
            f"target {target_ids[j]} is not tied to target {target_ids[0]}: no chain of views sees it together with "
            f"a target placed from {target_ids[0]} (it was seen in {shown}); add stops where two targets are in view")
    Q = np.tile(np.eye(3), (T, 1, 1))
    p = np.zeros((T, 3))
    order = sorted(parent, key=lambda j: _depth(parent, j))
    for b in order[1:]:
        a = parent[b]
        views = np.flatnonzero(ok[:, a] & ok[:, b])
        Qab, pab = _relative(R_cam_target, t_cam_target, a, b, views)
        Q[b] = Q[a] @ Qab
        p[b] = Q[a] @ pab + p[a]
    return Q, p, ties


def _depth(parent: dict[int, int], j: int) -> int:
    d = 0
    while parent[j] >= 0:
        j = parent[j]
        d += 1
    return d
