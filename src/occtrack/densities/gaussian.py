"""Gaussian components as arrays: Kalman predict, likelihood and update for all at once.

A single-object density is a mixture of Gaussian components. Each component's state splits into
B independent blocks of d dimensions (for image boxes: horizontal and vertical, each
(centre, velocity, half-size)), so a set of K components is held as

    means (K, B, d)    covariances (K, B, d, d)

and a block-diagonal covariance is never stored as a full matrix. Measurements are linear per
block, z_b = H x_b + e with e ~ N(0, R), p rows per block; a row of one measurement may be
missing (`observed` False), and the likelihood and update then use the rows that are present.

    predicted measurement  zhat = H m                 innovation covariance  S = H P H' + R
    log-likelihood         log N(z; zhat, S)
    Kalman gain            G = P H' S^-1              update  m + G (z - zhat),
                                                              (I - G H) P (I - G H)' + G R G'

filterpy and Stone Soup update one state at a time; these functions update every component
against every measurement (or every chosen pair) in a few array operations, which is what a
mixture filter with thousands of components needs, so they are written here.
"""

from __future__ import annotations

import numpy as np

LOG_2PI = float(np.log(2.0 * np.pi))


def predict(means: np.ndarray, covs: np.ndarray, F: np.ndarray,
            Q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Linear-Gaussian prediction of every component: m <- F m, P <- F P F' + Q.

    F and Q are (d, d) or (B, d, d)."""
    if F.ndim == 3:
        return np.einsum("bij,kbj->kbi", F, means), F @ covs @ np.swapaxes(F, -1, -2) + Q
    K, B, d = means.shape
    means = (means.reshape(-1, d) @ F.T).reshape(K, B, d)
    FP = np.swapaxes((covs.reshape(-1, d) @ F.T).reshape(K, B, d, d), -1, -2)
    covs = (FP.reshape(-1, d) @ F.T).reshape(K, B, d, d) + Q
    return means, covs


def innovation(means: np.ndarray, covs: np.ndarray, H: np.ndarray,
               R: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Predicted measurements zhat (K, B, p), innovation covariances S (K, B, p, p) and the
    cross covariances P H' (K, B, d, p) of every component.

    Products are taken as tall two-dimensional matrix products (one BLAS call each) rather than
    K B small stacked ones."""
    K, B, d = means.shape
    p = H.shape[0]
    zhat = (means.reshape(-1, d) @ H.T).reshape(K, B, p)
    PHt = (covs.reshape(-1, d) @ H.T).reshape(K, B, d, p)
    S = (np.swapaxes(PHt, -1, -2).reshape(-1, d) @ H.T).reshape(K, B, p, p) + R
    return zhat, S, PHt


def inv_logdet(S: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Inverses and log-determinants of a stack of symmetric positive definite matrices, in
    closed form for 1 x 1 and 2 x 2."""
    p = S.shape[-1]
    if p == 1:
        return 1.0 / S, np.log(S[..., 0, 0])
    if p == 2:
        a, b, c = S[..., 0, 0], S[..., 0, 1], S[..., 1, 1]
        det = a * c - b * b
        inv = np.empty_like(S)
        inv[..., 0, 0] = c / det
        inv[..., 1, 1] = a / det
        inv[..., 0, 1] = inv[..., 1, 0] = -b / det
        return inv, np.log(det)
    return np.linalg.inv(S), np.linalg.slogdet(S)[1]


def patterns(observed_b: np.ndarray) -> list[tuple[np.ndarray, np.ndarray | slice]]:
    """Group measurements by the rows they observe in one block: [(rows, columns)], one entry
    per distinct pattern, in a fixed order (a slice when every measurement observes all)."""
    p = observed_b.shape[1]
    if observed_b.all():
        return [(np.arange(p), slice(None))]
    keys = observed_b @ (1 << np.arange(p))
    out = []
    for key in np.unique(keys):
        cols = np.flatnonzero(keys == key)
        out.append((np.flatnonzero(observed_b[cols[0]]), cols))
    return out


def _quadratic_features(z: np.ndarray) -> np.ndarray:
    """Rows z_i z_j (i <= j), z_i and 1 of measurements z (M, p): (p(p+1)/2 + p + 1, M)."""
    i, j = np.triu_indices(z.shape[1])
    return np.concatenate([(z[:, i] * z[:, j]).T, z.T, np.ones((1, len(z)))])


def _quadratic_coefficients(zhat: np.ndarray, Sinv: np.ndarray, const: np.ndarray) -> np.ndarray:
    """Coefficients c_k with c_k . features(z) = (z - zhat_k)' Sinv_k (z - zhat_k) + const_k."""
    p = zhat.shape[1]
    i, j = np.triu_indices(p)
    a = Sinv[:, i, j] * np.where(i == j, 1.0, 2.0)
    Sz = (Sinv * zhat[:, None, :]).sum(axis=2)
    c = (zhat * Sz).sum(axis=1) + const
    return np.concatenate([a, -2.0 * Sz, c[:, None]], axis=1)


def loglik(means: np.ndarray, covs: np.ndarray, H: np.ndarray, R: np.ndarray, z: np.ndarray,
           observed: np.ndarray | None = None) -> np.ndarray:
    """log N(z_j; H m_k, H P_k H' + R) for every component k and measurement j: (K, M).

    z is (M, B, p); `observed` (M, B, p) marks the rows that were measured (all when None). A
    block with no observed row contributes nothing."""
    zhat, S, _ = innovation(means, covs, H, R)
    return loglik_from_innovation(zhat, S, z, observed)


def loglik_from_innovation(zhat: np.ndarray, S: np.ndarray, z: np.ndarray,
                           observed: np.ndarray | None = None) -> np.ndarray:
    """`loglik` from predicted measurements zhat (K, B, p) and innovation covariances S.

    The quadratic form is expanded, (z - zhat)' S^-1 (z - zhat) = sum_ij A_ij z_i z_j
    - 2 (S^-1 zhat)' z + zhat' S^-1 zhat, so all K x M pairs of a block cost one matrix product;
    measurements are grouped by their pattern of observed rows, one small inverse per component
    and pattern."""
    K, M = zhat.shape[0], z.shape[0]
    out = np.zeros((K, M))
    if K == 0 or M == 0:
        return out
    if observed is None:
        observed = np.ones(z.shape, dtype=bool)
    for b in range(z.shape[1]):
        for rows, cols in patterns(observed[:, b]):
            if len(rows) == 0:
                continue
            Sinv, logdet = inv_logdet(S[:, b][:, rows][:, :, rows])
            coef = _quadratic_coefficients(zhat[:, b, rows], Sinv, logdet + len(rows) * LOG_2PI)
            out[:, cols] -= 0.5 * (coef @ _quadratic_features(z[cols, b][:, rows]))
    return out


def update(means: np.ndarray, covs: np.ndarray, H: np.ndarray, R: np.ndarray, z: np.ndarray,
           observed: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Kalman update of component n by measurement n, for n aligned pairs: means (n, B, d),
    covs (n, B, d, d), z and `observed` (n, B, p).

    A missing row is given H row 0, innovation 0 and unit noise, which makes its gain column
    exactly zero: the update is the one that uses the observed rows only. Joseph form, so
    covariances stay symmetric and positive definite."""
    if observed is None:
        observed = np.ones(z.shape, dtype=bool)
    mask = observed.astype(float)
    Hn = H * mask[..., None]  # (n, B, p, d)
    Rn = R * (mask[..., :, None] * mask[..., None, :])
    Rn = Rn + np.eye(H.shape[0]) * (1.0 - mask)[..., None]
    resid = (z - means @ H.T) * mask
    PHt = covs @ np.swapaxes(Hn, -1, -2)
    S = Hn @ PHt + Rn
    G = PHt @ inv_logdet(S)[0]
    new_means = means + (G @ resid[..., None])[..., 0]
    A = np.eye(means.shape[-1]) - G @ Hn
    new_covs = A @ covs @ np.swapaxes(A, -1, -2) + G @ Rn @ np.swapaxes(G, -1, -2)
    new_covs = 0.5 * (new_covs + np.swapaxes(new_covs, -1, -2))
    return new_means, new_covs
