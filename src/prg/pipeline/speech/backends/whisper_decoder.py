"""Whisper's text decoder in PyTorch, for scoring given transcripts by teacher forcing.

CTranslate2 runs Whisper's encoder and free decoding fast, but it has no call that returns the
probability of a *given* token sequence followed by end-of-text: ``Whisper.align`` renormalises
over text tokens only (no end-of-text), and ``Whisper.generate`` with the sequence as a forced
prefix steps through it one decoder call per token, with a fixed cost per call and per batch
row (measured with CTranslate2 4.x on tiny.en: about 12 ms for one short word, 32 ms for two).
Rescoring a lexicon needs exactly those probabilities, for a few words at once, on one encoder
output. This module runs the same decoder on the same weights as one batched forward pass: the
cross-attention keys and values of the encoder output are computed once and shared by every
candidate row (``transformers``' Whisper decoder would recompute them per row).

The weights are read from the CTranslate2 model folder's ``model.bin`` (Whisper's decoder is
stored there in float16; CTranslate2 quantises it to int8 at load time) by
:func:`read_model_bin`, which only unpacks numbers: nothing in the file is executed. The linear
maps run in bfloat16 (half the memory traffic of float32), layer norms and the residual stream
in float32. The token log-probabilities agree with CTranslate2's int8 decoder to within 0.3
nats (``tests/test_speech.py``); a float32 projection onto the vocabulary changed them by at
most 0.03 on four words, and rescoring got as many words right as with CTranslate2's decoder
on bench_speech's 96 hard utterances and on two held-out sets (240 more).
"""

from __future__ import annotations

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
        self.projection = self.embedding.to(torch.bfloat16)
        self.positions = tensor("position_encodings/encodings")
        self.final_norm = (tensor("layer_norm/gamma"), tensor("layer_norm/beta"))
        self.layers = []
        while f"decoder/layer_{len(self.layers)}/ffn/linear_0/weight" in variables:
            prefix = f"decoder/layer_{len(self.layers)}/"
            layer = {
                name[len(prefix) :]: tensor(name[len("decoder/") :])
                for name in variables
                if name.startswith(prefix)
            }
            # the linear maps in bfloat16 (half float32's memory traffic), layer norms in float32
            for name in [n for n in layer if "linear" in n]:
                layer[name] = layer[name].to(torch.bfloat16)
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
                    for part in self._linear(states, layer, "attention/linear_1").chunk(2, dim=-1)
                )
                for layer in self.layers
            ]

    def _heads(self, x):
        """(..., length, width) -> (..., heads, length, head size)."""
        return x.unflatten(-1, (self.heads, -1)).transpose(-3, -2)

    def hidden(self, tokens, memory):
        """The final normalised hidden states (views, rows, length, width) of the token rows
        ``tokens`` (rows, length) attending to each view's ``memory`` (:meth:`memory`). Causal,
        so padding after a row's tokens does not change its states."""
        import torch.nn.functional as F

        rows, length = tokens.shape
        n_views = memory[0][0].shape[0]
        width = self.embedding.shape[1]
        x = (self.embedding[tokens] + self.positions[:length]).expand(n_views, -1, -1, -1)
        for layer, (keys, values) in zip(self.layers, memory, strict=True):
            h = self._norm(x, layer, "self_attention")
            q, k, v = self._linear(h, layer, "self_attention/linear_0").chunk(3, dim=-1)
            a = F.scaled_dot_product_attention(
                self._heads(q), self._heads(k), self._heads(v), is_causal=True
            )
            x = x + self._linear(a.transpose(-3, -2).flatten(-2), layer, "self_attention/linear_1")
            # a view's rows all attend to its memory: their queries are stacked into one
            # sequence, so the keys and values are not copied per row
            q = self._linear(self._norm(x, layer, "attention"), layer, "attention/linear_0")
            a = F.scaled_dot_product_attention(
                self._heads(q.reshape(n_views, rows * length, width)), keys, values
            )
            a = a.transpose(-3, -2).reshape(n_views, rows, length, width)
            x = x + self._linear(a, layer, "attention/linear_2")
            h = F.gelu(self._linear(self._norm(x, layer, "ffn"), layer, "ffn/linear_0"))
            x = x + self._linear(h, layer, "ffn/linear_1")
        return F.layer_norm(x, (width,), *self.final_norm)

    @staticmethod
    def _linear(x, layer: dict, name: str):
        """``layer``'s linear map ``name`` of ``x``, in the weights' precision, as float32."""
        import torch.nn.functional as F

        weight = layer[f"{name}/weight"]
        return F.linear(x.to(weight.dtype), weight, layer[f"{name}/bias"]).float()

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

        logits = (hidden.to(self.projection.dtype) @ self.projection.T).float()
        return torch.log_softmax(logits, dim=-1)

    def first_logits(self, memory, start: list[int], tokens: list[int]) -> np.ndarray:
        """The unnormalised logits (views, tokens) of ``tokens`` as the next token after
        ``start``: enough to rank them, without the projection onto the whole vocabulary."""
        import torch

        with torch.inference_mode():
            last = self.hidden(torch.tensor([start]), memory)[:, 0, -1]
            return (last @ self.embedding[tokens].T).numpy()

    def next_token(self, memory, start: list[int], prefixes) -> dict[tuple[int, ...], np.ndarray]:
        """``log P(next token | start + p)``, an array (views, vocabulary), for each distinct
        token tuple ``p`` in ``prefixes``, by teacher forcing: the prefixes that extend no
        other are the rows of one batched pass, and each prefix is read at its position."""
        import torch

        wanted = sorted(set(prefixes))
        rows = [p for p in wanted if not any(o != p and o[: len(p)] == p for o in wanted)]
        length = len(start) + max(len(r) for r in rows)
        tokens = torch.zeros((len(rows), length), dtype=torch.long)
        for i, row in enumerate(rows):
            tokens[i, : len(start) + len(row)] = torch.tensor([*start, *row])
        row_of = [next(i for i, r in enumerate(rows) if r[: len(p)] == p) for p in wanted]
        with torch.inference_mode():
            hidden = self.hidden(tokens, memory)
            picked = hidden[:, row_of, [len(start) - 1 + len(p) for p in wanted]]
            logp = self.log_probabilities(picked).numpy()
        return {p: logp[:, i] for i, p in enumerate(wanted)}
