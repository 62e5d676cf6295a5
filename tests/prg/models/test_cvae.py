"""Tests of ``prg.models.cvae`` (moved from the suite on: the model families (CVAE, AVAE, MUSE),
their appendix networks and the Lightning module.

Everything runs on tiny seeded in-memory batches, except the ``fast_dev_run`` checks which use
the real :class:`~prg.data.datamodule.PRGDataModule` on the session's small prepared dataset)."""

from __future__ import annotations

from prg.models.cvae import CVAE
from tests.helpers.models import linear_sizes


def test_cvae_networks_take_the_one_hot_label_concatenated():
    model = CVAE()
    assert linear_sizes(model.encoder)[0] == (200 + 62, 512)
    assert linear_sizes(model.decoder)[0] == (16 + 62, 512)
