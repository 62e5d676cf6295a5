"""Whisper's text decoder in PyTorch, for scoring given transcripts by teacher forcing.

CTranslate2 runs Whisper's encoder and free decoding fast, but it has no call that returns the
probability of a *given* token sequence followed by end-of-text: ``Whisper.align`` renormalises
over text tokens only (no end-of-text), and ``Whisper.generate`` with the sequence as a forced
prefix steps through it one decoder call per token, with a fixed cost per call and per batch
row (measured with CTranslate2 4.x on tiny.en: about 12 ms for one short word, 32 ms for two).
Rescoring a lexicon needs exactly those probabilities, for a few words at once, on one encoder
output. This module runs the same decoder on the same weights as one forward pass over the
prefix tree of every written variant being scored (:func:`prefix_tree`: each shared prefix
decoded once, each node attending to its ancestors), and the cross-attention keys and values of
the encoder output are computed once and shared by every node (``transformers``' Whisper
decoder would recompute them per row).

The weights are read from the CTranslate2 model folder's ``model.bin`` (Whisper's decoder is
stored there in float16; CTranslate2 quantises it to int8 at load time) by
:func:`read_model_bin`, which only unpacks numbers: nothing in the file is executed. The linear
maps run in bfloat16 (half the memory traffic of float32), layer norms and the residual stream
in float32. The token log-probabilities agree with CTranslate2's int8 decoder to within 0.3
nats (``tests/prg/pipeline/speech/backends/test_whisper.py``); a float32 projection onto the vocabulary changed them by at
most 0.03 on four words, and rescoring got as many words right as with CTranslate2's decoder
on bench_speech's 96 hard utterances and on two held-out sets (240 more).
"""

from __future__ import annotations

import functools
import struct
from pathlib import Path

import numpy as np

# CTranslate2's DataType enumeration (include/ctranslate2/types.h), as stored in model.bin
_DTYPES = {0: np.float32, 1: np.int8, 2: np.int16, 3: np.int32, 4: np.float16}
_MIN_BINARY_VERSION = 4  # the first with a stored data type per variable
_GELU = 3  # CTranslate2's ActivationType::GELU


def read_model_bin(path: Path) -> dict[str, np.ndarray]:
    """The variables of a CTranslate2 ``model.bin`` (binary format version 4 or later), by
    name, aliases resolved to their targets' arrays.

    Raises
    ------
    ValueError
        ``path`` is not such a file (wrong version, unknown data type, truncated).
    """
    data = Path(path).read_bytes()
    offset = 0

    def take(fmt: str) -> tuple:
        nonlocal offset
        values = struct.unpack_from(fmt, data, offset)
        offset += struct.calcsize(fmt)
        return values

    def text() -> str:
        nonlocal offset
        (size,) = take("<H")
        value = data[offset : offset + size].rstrip(b"\0").decode()
        offset += size
        return value

    try:
        (version,) = take("<I")
        if version < _MIN_BINARY_VERSION:
            raise ValueError(f"binary version {version}, expected {_MIN_BINARY_VERSION} or later")
        text(), take("<I")  # model spec name and revision
        variables: dict[str, np.ndarray] = {}
        for _ in range(take("<I")[0]):
            name = text()
            (rank,) = take("<B")
            shape = take(f"<{rank}I")
            type_id, size = take("<BI")
            if type_id not in _DTYPES:
                raise ValueError(f"variable {name!r} has unknown data type {type_id}")
            dtype = np.dtype(_DTYPES[type_id])
            if size != dtype.itemsize * int(np.prod(shape)) or offset + size > len(data):
                raise ValueError(f"variable {name!r} has a wrong or truncated payload")
            variables[name] = np.frombuffer(data, dtype, int(np.prod(shape)), offset).reshape(shape)
            offset += size
        for _ in range(take("<I")[0]):
            alias, target = text(), text()
            variables[alias] = variables[target]
    except struct.error as err:
        raise ValueError(f"truncated file ({err})") from None
    return variables


class WhisperDecoder:
    """Whisper's decoder (pre-norm Transformer, learned positions, GELU, output layer tied to
    the token embedding) on the CPU, for teacher-forced scoring: linear maps in bfloat16, the
    rest in float32."""

    def __init__(self, variables: dict[str, np.ndarray]) -> None:
        import torch

        def tensor(name: str):
            return torch.from_numpy(variables[f"decoder/{name}"].astype(np.float32))

        if int(variables["decoder/activation"]) != _GELU or not int(variables["decoder/pre_norm"]):
            raise ValueError("not a Whisper decoder (expected pre-norm layers with GELU)")
        self.heads = int(variables["decoder/num_heads"])
        self.embedding = tensor("embeddings/weight")
        self.projection = _LinearMap(self.embedding, None)
        self.positions = tensor("position_encodings/encodings")
        self.final_norm = (tensor("layer_norm/gamma"), tensor("layer_norm/beta"))
        self.layers = []
        while f"decoder/layer_{len(self.layers)}/ffn/linear_0/weight" in variables:
            prefix = f"layer_{len(self.layers)}/"
            names = [n[len("decoder/") :] for n in variables if n.startswith("decoder/" + prefix)]
            # layer norms in float32, linear maps in bfloat16 (_LinearMap)
            layer = {n[len(prefix) :]: tensor(n) for n in names if "linear" not in n}
            for name in {n.rsplit("/", 1)[0] for n in names if "linear" in n}:
                layer[name[len(prefix) :]] = _LinearMap(
                    tensor(f"{name}/weight"), tensor(f"{name}/bias")
                )
            self.layers.append(layer)

    @classmethod
    def from_model_folder(cls, folder: Path) -> WhisperDecoder:
        """The decoder stored in a CTranslate2 Whisper model folder."""
        return cls(read_model_bin(Path(folder) / "model.bin"))

    def memory(self, encoded: np.ndarray) -> list:
        """Per layer, the cross-attention keys and values (views, heads, frames, head size) of
        encoder outputs ``encoded`` (views, frames, width): one per view of the audio."""
        import torch

        states = torch.from_numpy(np.asarray(encoded, dtype=np.float32))
        with torch.inference_mode():
            return [
                tuple(
                    self._heads(part)
                    for part in layer["attention/linear_1"](states).chunk(2, dim=-1)
                )
                for layer in self.layers
            ]

    def _heads(self, x):
        """(..., length, width) -> (..., heads, length, head size)."""
        return x.unflatten(-1, (self.heads, -1)).transpose(-3, -2)

    def hidden(self, tokens, positions, visible, memory):
        """The final normalised hidden states (views, tokens, width) of ``tokens`` (n,) at
        ``positions`` (n,), where token ``i`` attends to the tokens ``j`` with ``visible[i, j]``
        (a bool (n, n) tensor) and to each view's ``memory`` (:meth:`memory`).

        A causal mask over one sequence decodes that sequence; an ancestor mask over a prefix
        tree (:func:`prefix_tree`) decodes every branch at once, each shared prefix once."""
        import torch.nn.functional as F

        n_views = memory[0][0].shape[0]
        width = self.embedding.shape[1]
        x = (self.embedding[tokens] + self.positions[positions]).expand(n_views, -1, -1)
        for layer, (keys, values) in zip(self.layers, memory, strict=True):
            h = self._norm(x, layer, "self_attention")
            q, k, v = layer["self_attention/linear_0"](h).chunk(3, dim=-1)
            a = F.scaled_dot_product_attention(
                self._heads(q), self._heads(k), self._heads(v), attn_mask=visible
            )
            x = x + layer["self_attention/linear_1"](a.transpose(-3, -2).flatten(-2))
            q = layer["attention/linear_0"](self._norm(x, layer, "attention"))
            a = F.scaled_dot_product_attention(self._heads(q), keys, values)
            x = x + layer["attention/linear_2"](a.transpose(-3, -2).flatten(-2))
            h = layer["ffn/linear_0"](self._norm(x, layer, "ffn"), gelu=True)
            x = x + layer["ffn/linear_1"](h)
        return F.layer_norm(x, (width,), *self.final_norm)

    @staticmethod
    def _norm(x, layer: dict, block: str):
        import torch.nn.functional as F

        return F.layer_norm(
            x, (x.shape[-1],), layer[f"{block}/layer_norm/gamma"], layer[f"{block}/layer_norm/beta"]
        )

    def log_probabilities(self, hidden):
        """Next-token log-probabilities (..., vocabulary), float32, of hidden states (...,
        width). The projection onto the vocabulary (51,864 tokens for Whisper) is most of the
        cost for a short word; it runs in bfloat16 (:attr:`projection`)."""
        import torch

        logits = self.projection(hidden)
        return torch.log_softmax(logits, dim=-1)

    def first_logits(self, memory, start: list[int], tokens: list[int]) -> np.ndarray:
        """The unnormalised logits (views, tokens) of ``tokens`` as the next token after
        ``start``: enough to rank them, without the projection onto the whole vocabulary."""
        import torch

        with torch.inference_mode():
            last = self.hidden(*prefix_tree(start, [()]), memory)[:, -1]
            return (last @ self.embedding[tokens].T).numpy()

    def next_token(self, memory, start: list[int], prefixes) -> dict[tuple[int, ...], np.ndarray]:
        """``log P(next token | start + p)``, an array (views, vocabulary), for each distinct
        token tuple ``p`` in ``prefixes`` and their prefixes, by teacher forcing: one pass over
        their prefix tree (:func:`prefix_tree`)."""
        import torch

        wanted = sorted({p[:k] for p in prefixes for k in range(len(p) + 1)})
        with torch.inference_mode():
            hidden = self.hidden(*prefix_tree(start, wanted), memory)
            # the tree's nodes are the start tokens, then ``wanted``'s non-empty prefixes
            logp = self.log_probabilities(hidden[:, len(start) - 1 :]).numpy()
        return {p: logp[:, i] for i, p in enumerate(wanted)}


def prefix_tree(start: list[int], prefixes: list[tuple[int, ...]]):
    """The token tree of ``start`` followed by each of ``prefixes`` (sorted, distinct, closed
    under taking prefixes, ``()`` first), as :meth:`WhisperDecoder.hidden`'s inputs: tokens,
    positions, and the mask of each node's ancestors and itself.

    Its nodes are the start tokens, then one per non-empty prefix (its last token), so the
    decoder state after ``start + p`` is that of node ``len(start) - 1 + prefixes.index(p)``.
    Each shared prefix is decoded once: for bench_speech's words, two at a time, the tree has
    55-62% of the tokens of one padded row per variant that no other extends. (Tree-structured
    attention, as used to verify several candidate continuations in one pass.)
    """
    import torch

    node = {(): len(start) - 1}
    parents = list(range(-1, len(start) - 1))
    tokens, positions = list(start), list(range(len(start)))
    for prefix in prefixes[1:]:
        node[prefix] = len(tokens)
        parents.append(node[prefix[:-1]])
        tokens.append(prefix[-1])
        positions.append(positions[parents[-1]] + 1)
    visible = torch.zeros((len(tokens), len(tokens)), dtype=torch.bool)
    for i, parent in enumerate(parents):
        if parent >= 0:
            visible[i] = visible[parent]
        visible[i, i] = True
    return torch.tensor(tokens), torch.tensor(positions), visible


class _LinearMap:
    """``x @ weight.T + bias`` (optionally followed by GELU) in bfloat16, returned as float32.

    Where oneDNN runs bfloat16, the weight is reordered once into its blocked layout
    (``torch.ops.mkldnn``: what ``torch.compile`` does for frozen CPU weights, without
    compiling); ``F.linear`` otherwise reorders it on every call. Measured on bench_speech's
    machine (one thread, a decoder pass of 2 to 12 tokens): 40-45 against 70-90 microseconds per
    384 x 1152 map, and 1.8-2.0 against 2.7-3.6 ms for the projection onto the vocabulary.
    """

    def __init__(self, weight, bias) -> None:
        import torch

        self.packed = _onednn_bfloat16()
        self.weight = weight.to(torch.bfloat16)
        if self.packed:  # oneDNN's layout only: it is not a plain (out, in) tensor any more
            self.weight = torch.ops.mkldnn._reorder_linear_weight(self.weight)
        self.bias = None if bias is None else bias.to(torch.bfloat16)

    def __call__(self, x, gelu: bool = False):
        import torch
        import torch.nn.functional as F

        # on a 2-D input: oneDNN took 165 ms for a (1, 9, 384) batch, 3 ms for (9, 384)
        flat = x.reshape(-1, x.shape[-1]).to(torch.bfloat16)
        if self.packed:
            y = torch.ops.mkldnn._linear_pointwise(
                flat, self.weight, self.bias, "gelu" if gelu else "none", [], "none" if gelu else ""
            )
        else:
            y = F.linear(flat, self.weight, self.bias)
            y = F.gelu(y) if gelu else y
        return y.float().reshape(*x.shape[:-1], -1)


@functools.cache
def _onednn_bfloat16() -> bool:
    """Whether this PyTorch build runs bfloat16 linear maps on prepacked oneDNN weights."""
    import torch

    try:
        return bool(
            torch.backends.mkldnn.is_available()
            and torch.ops.mkldnn._is_mkldnn_bf16_supported()
            and hasattr(torch.ops.mkldnn, "_linear_pointwise")
        )
    except (AttributeError, RuntimeError):
        return False
