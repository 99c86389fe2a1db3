"""The pieces of an exported network file, in numpy: MLP layers, the observation normalisation, the safetensors
header with its JSON description (read without torch)."""

from __future__ import annotations

import hashlib
import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

FORMAT = "fastrl.networks/1"
HEADER_KEY = "fastrl"  # the safetensors header metadata key holding the JSON description


def file_sha256(path: Path) -> str:
    """Hex sha256 of a file's bytes."""
    return hashlib.sha256(path.read_bytes()).hexdigest()


@dataclass(frozen=True)
class Mlp:
    """A chain of linear layers and activations evaluated in float32 with numpy, as torch evaluates them."""

    layers: tuple

    def __call__(self, x: np.ndarray) -> np.ndarray:
        for kind, a, b in self.layers:
            if kind == "linear":
                x = x @ a if b is None else x @ a + b
            elif kind == "tanh":
                x = np.tanh(x)
            elif kind == "relu":
                x = np.maximum(x, np.float32(0.0))
            else:  # hardtanh
                x = np.clip(x, np.float32(a), np.float32(b))
        return x


def build_mlp(name: str, layers: list[dict], tensors: dict[str, np.ndarray]) -> Mlp:
    """The part `name` from its JSON layer list and the tensors, checking every shape."""
    built = []
    for i, layer in enumerate(layers):
        kind = layer["type"]
        if kind == "linear":
            w = np.asarray(tensors[f"{name}.{i}.weight"], np.float32)
            b = np.asarray(tensors[f"{name}.{i}.bias"], np.float32) if layer["bias"] else None
            if tuple(w.shape) != (layer["out"], layer["in"]) or (b is not None and tuple(b.shape) != (layer["out"],)):
                raise ValueError(f"layer {name}.{i}: tensor shapes do not match {layer}")
            built.append(("linear", np.ascontiguousarray(w.T), b))  # x @ W^T, as torch's linear
        elif kind in ("tanh", "relu"):
            built.append((kind, None, None))
        elif kind == "hardtanh":
            built.append((kind, float(layer["min"]), float(layer["max"])))
        else:
            raise ValueError(f"layer {name}.{i}: unknown type {kind!r}")
    return Mlp(tuple(built))


@dataclass(frozen=True)
class ObsNorm:
    """VecNormalize's observation transform clip((obs - mean) / sqrt(var + eps), -clip, clip); identity if empty."""

    obs_dim: int
    mean: np.ndarray | None = None
    var: np.ndarray | None = None
    clip: float = 0.0
    epsilon: float = 0.0

    def __call__(self, obs: np.ndarray) -> np.ndarray:
        x = np.asarray(obs, dtype=np.float64)
        if x.ndim != 2 or x.shape[1] != self.obs_dim:
            raise ValueError(f"expected a batch of observations of shape (n, {self.obs_dim}), got {tuple(x.shape)}")
        if self.mean is not None:
            x = np.clip((x - self.mean) / np.sqrt(self.var + self.epsilon), -self.clip, self.clip)
        return x.astype(np.float32)


def build_norm(meta: dict, tensors: dict[str, np.ndarray]) -> ObsNorm:
    """The observation normalisation stored in a pair."""
    obs_dim, norm = int(meta["obs_dim"]), meta["obs_norm"]
    if norm is None:
        return ObsNorm(obs_dim)
    mean, var = np.asarray(tensors["obs_norm.mean"], np.float64), np.asarray(tensors["obs_norm.var"], np.float64)
    if mean.shape != (obs_dim,) or var.shape != (obs_dim,):
        raise ValueError(f"normalisation statistics of shape {tuple(mean.shape)}, expected ({obs_dim},)")
    return ObsNorm(obs_dim, mean, var, float(norm["clip"]), float(norm["epsilon"]))


@dataclass(frozen=True)
class Loaded:
    """One pair as read: its JSON file and contents, normalisation, MLP parts and tensors."""

    path: Path
    meta: dict
    norm: ObsNorm
    parts: dict[str, Mlp]
    tensors: dict[str, np.ndarray]

    def variant(self, key: str, needs: dict[str, tuple[str, ...]]) -> str:
        """meta[key], one of needs' keys, whose required parts or tensors were all saved; else a clear error."""
        value = self.meta.get(key)
        if value not in needs:
            raise ValueError(f"{self.path}: {key} must be one of {tuple(needs)}, got {value!r}")
        missing = [n for n in needs[value] if n not in self.parts and n not in self.tensors]
        if missing:
            raise ValueError(f"{self.path}: {missing} missing for {key}={value!r}")
        return value


def _read_safetensors(path: Path) -> tuple[dict, dict[str, np.ndarray]]:
    """The JSON description in a safetensors header and the tensors; the file's sha256 added as its identity."""
    from safetensors import safe_open
    from safetensors.numpy import load_file

    try:
        with safe_open(str(path), "np") as f:
            header = f.metadata() or {}
        tensors = load_file(str(path))
    except Exception as e:  # safetensors reports truncation and bad headers with its own error types
        raise ValueError(f"{path}: not a readable safetensors file ({e})") from e
    if HEADER_KEY not in header:
        raise ValueError(f"{path}: no {HEADER_KEY!r} description in its header metadata")
    try:
        meta = json.loads(header[HEADER_KEY])
    except json.JSONDecodeError as e:
        raise ValueError(f"{path}: header metadata {HEADER_KEY!r} is not valid JSON ({e})") from e
    if not isinstance(meta, dict) or meta.get("format") != FORMAT:
        raise ValueError(f"{path}: not a {FORMAT} file")
    return meta | {"sha256": file_sha256(path)}, tensors


def read_pair(directory: Path, name: str) -> Loaded:
    """NAME.safetensors, or FileNotFoundError/ValueError naming the bad file."""
    js = directory / f"{name}.safetensors"
    if not js.is_file():
        raise FileNotFoundError(f"{js}: file not found")
    meta, tensors = _read_safetensors(js)
    try:
        parts = {p: build_mlp(p, layers, tensors) for p, layers in meta["parts"].items()}
        return Loaded(js, meta, build_norm(meta, tensors), parts, tensors)
    except KeyError as e:
        raise ValueError(f"{js}: missing key {e} (in the description, or as a tensor)") from e
    except (TypeError, AttributeError, ValueError) as e:
        raise ValueError(f"{js}: malformed ({e})") from e
