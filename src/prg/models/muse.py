"""MUSE (Vasco et al. 2022): a hierarchical multimodal VAE robust to missing modalities.

Bottom level: one VAE per modality m, q(z_m | x_m) and g_m(z_m) (the appendix networks, latent 16).
Top level: per modality a *top expert* h_m: z_m -> (mu, logvar) of the top latent c (8 dims) and a
*top decoder* d_m: c -> z_m (MLPs 512 x 3). The top posterior from any subset S of modalities is
the product of the experts of S **and the prior expert N(0, I)**; a missing modality is an expert
left out. Written for any number of modalities >= 2.

Loss per sample, averaged over the batch (weights by role, the paper's defaults):

- ``sum_m lambda_m Rec_m(x_m, g_m(z_m)) + alpha_m KL(q(z_m | x_m) || N(0, I))``   bottom ELBOs
- ``+ sum_m gamma_m ||d_m(c) - sg(z_m)||^2``  top reconstruction of the (detached) bottom codes
- ``+ beta KL(q(c | sg(z_all)) || N(0, I))``  top KL
- ``+ delta * mean over proper non-empty subsets S of SKL(q(c | sg(z_S)), q(c | sg(z_all)))``
- ``+ mode_seeking * sum_{m != label} gamma_m min_{j: y_j = y} ||d_m(mu_label) - sg(z_m,j)||^2``
  with ``mu_label`` the mean of q(c | label) (0 in the paper; :meth:`MUSE._mode_seeking`): the
  label posterior's mean decodes to the nearest code of its class, a real style, not the class's
  average code; the candidates j are the batch's samples or, with ``mode_bank`` N > 0, the last
  N samples of each class seen in training

The top KL and subset SKL, the top level's regularisers, are multiplied by ``kl_scale`` (1
outside training), which the training loop can ramp up from 0: both are minimised by experts
that say nothing (an expert with a huge variance leaves every product unchanged), so at full
weight from the first step, while the bottom codes still move, an expert can be driven to a
variance so large that its gradients vanish and it never recovers (measured: the label expert's
log-variance at 27 after 350 steps at learning rate 3e-3). The reference code warms up beta
the same way.

The top level never sends gradients into the bottom VAEs; every subset is computed on every batch.
Cross-modal generation: each available x_m -> bottom posterior mean -> h_m -> product with the
prior -> c (mean, or sampled) -> x_target = g_target(d_target(c)).
"""

from __future__ import annotations

from itertools import combinations

import torch
from torch import nn

from prg.alphabet import NUM_CLASSES
from prg.models.base import Gaussian, ImportancePath, Inputs, MultimodalVAE
from prg.models.components import ClassRing, GaussianHead, mlp, nearest_same_class
from prg.models.fusion import kl_standard_normal, product_of_experts, reparameterise, symmetric_kl
from prg.models.modalities import MODALITIES


def proper_subsets(modalities: tuple[str, ...]) -> list[tuple[str, ...]]:
    """Every proper non-empty subset, smallest first (3 singletons + 3 pairs for 3 modalities)."""
    return [s for r in range(1, len(modalities)) for s in combinations(modalities, r)]


class TopExpert(nn.Module):
    """h_m: z_m (16) -> FC 512 x3 -> (mu, logvar) of c (8)."""

    def __init__(self, latent_dim: int, top_dim: int, hidden: int = 512):
        super().__init__()
        self.body = mlp([latent_dim, hidden, hidden, hidden])
        self.head = GaussianHead(hidden, top_dim)

    def forward(self, z: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
        return self.head(self.body(z))


class MUSE(MultimodalVAE):
    family = "muse"

    def __init__(
        self,
        modalities: tuple[str, ...] = ("traj", "label", "image"),
        latent_dim: int = 16,
        top_latent_dim: int = 8,
        traj_std: float = 0.1,
        lambdas: dict[str, float] | None = None,
        alphas: dict[str, float] | None = None,
        gammas: dict[str, float] | None = None,
        beta: float = 1.0,
        delta: float = 1.0,
        mode_seeking: float = 0.0,
        mode_bank: int = 0,
    ):
        super().__init__(tuple(modalities), latent_dim, traj_std)
        if len(self.modalities) < 2:
            raise ValueError("MUSE needs at least two modalities")
        default_lambda = {"traj": 1.0, "label": 50.0, "image": 1.0}  # the paper's; others 1

        def weights(given, default):
            return {m: float((given or {}).get(m, default(m))) for m in self.modalities}

        self.lambdas = weights(lambdas, lambda m: default_lambda.get(m, 1.0))
        self.alphas = weights(alphas, lambda m: 1.0)
        self.gammas = weights(gammas, lambda m: 10.0)
        self.beta, self.delta, self.mode_seeking = beta, delta, mode_seeking
        self.mode_bank = int(mode_bank)
        if self.mode_seeking and self.mode_bank and "label" in self.modalities:
            self.banks = nn.ModuleDict(
                {
                    m: ClassRing(NUM_CLASSES, self.mode_bank, latent_dim)
                    for m in self.modalities
                    if m != "label"
                }
            )
        self.kl_scale = 1.0  # the training loop's warm-up of the top-level regularisers
        self.top_latent_dim = top_latent_dim
        self.encoders = nn.ModuleDict(
            {m: MODALITIES[m].encoder(latent_dim) for m in self.modalities}
        )
        self.decoders = nn.ModuleDict(
            {m: MODALITIES[m].decoder(latent_dim) for m in self.modalities}
        )
        self.top_experts = nn.ModuleDict(
            {m: TopExpert(latent_dim, top_latent_dim) for m in self.modalities}
        )
        self.top_decoders = nn.ModuleDict(
            {m: mlp([top_latent_dim, 512, 512, 512, latent_dim], False) for m in self.modalities}
        )

    # ---- top level ----------------------------------------------------------------------
    def top_posterior(self, codes: dict[str, torch.Tensor]) -> Gaussian:
        """q(c | z_S): product of the given modalities' top experts and the prior expert."""
        return self._fuse({m: self.top_experts[m](z) for m, z in codes.items()})

    @staticmethod
    def _fuse(experts: dict[str, tuple[torch.Tensor, torch.Tensor]]) -> Gaussian:
        return Gaussian(
            *product_of_experts([e[0] for e in experts.values()], [e[1] for e in experts.values()])
        )

    def encode(self, inputs: Inputs) -> Gaussian:
        """q(c | x_S) for any non-empty subset S: bottom posterior means through the experts."""
        self.check_inputs(inputs)
        codes = {m: self.encoders[m](inputs[m])[0] for m in self.modalities if m in inputs}
        return self.top_posterior(codes)

    def decode(self, z: torch.Tensor, modality: str, inputs: Inputs | None = None) -> torch.Tensor:
        """x_m parameters from the top latent c: g_m(d_m(c))."""
        return self.decoders[modality](self.top_decoders[modality](z))

    imputes_missing = True

    def encode_imputed(self, inputs: Inputs, steps: int) -> Gaussian:
        """q(c | x_G, x^_M) after ``steps`` rounds of imputing the missing modalities M.

        q(c | x_G) from a subset G is broad: one label must cover every style of its letter, so
        its mean sits between the styles, and decoding it gives a blend that can read as
        another letter. Each round decodes the missing modalities from the current posterior
        mean (trajectory and pixel means, the most likely label), encodes them with their own
        bottom encoders and fuses them with the given ones: a deterministic form of the
        encoder-decoder imputation chain of Rezende, Mohamed & Wierstra (2014, sec. 5). The
        given modalities keep their experts in every round, so the posterior moves toward one
        style of what was given. ``steps=0`` is :meth:`encode`."""
        self.check_inputs(inputs)
        given = {m: self.encoders[m](inputs[m])[0] for m in self.modalities if m in inputs}
        missing = [m for m in self.modalities if m not in inputs]
        posterior = self.top_posterior(given)
        for _ in range(steps):
            codes = dict(given)
            for m in missing:  # the decoded mean as an input (a label: its most probable class)
                imputed = self.likelihoods.as_input(m, self.decode(posterior.mu, m))
                codes[m] = self.encoders[m](imputed)[0]
            posterior = self.top_posterior(codes)
        return posterior

    # ---- training -----------------------------------------------------------------------
    def elbo(self, batch: Inputs, inputs: Inputs | None = None) -> dict[str, torch.Tensor]:
        inputs = batch if inputs is None else inputs
        terms: dict[str, torch.Tensor] = {}
        loss = 0.0
        codes = {}
        for m in self.modalities:
            mu, logvar = self.encoders[m](inputs[m])
            z = reparameterise(mu, logvar)
            rec = -self.likelihoods.log_prob(m, self.decoders[m](z), batch[m]).mean()
            kl = kl_standard_normal(mu, logvar).mean()
            terms[f"rec_{m}"], terms[f"kl_{m}"] = rec, kl
            loss = loss + self.lambdas[m] * rec + self.alphas[m] * kl
            codes[m] = z.detach()  # the top level never trains the bottom VAEs

        experts = {m: self.top_experts[m](z) for m, z in codes.items()}  # each computed once
        q_all = self._fuse(experts)
        c = reparameterise(q_all.mu, q_all.logvar)
        for m in self.modalities:
            top_rec = (self.top_decoders[m](c) - codes[m]).pow(2).sum(-1).mean()
            terms[f"top_rec_{m}"] = top_rec
            loss = loss + self.gammas[m] * top_rec
        if self.mode_seeking and "label" in self.modalities:
            loss = loss + self.mode_seeking * self._mode_seeking(
                experts, codes, batch["label"], terms
            )
        terms["top_kl"] = kl_standard_normal(q_all.mu, q_all.logvar).mean()
        loss = loss + self.beta * self.kl_scale * terms["top_kl"]
        subset_posteriors = [
            self._fuse({m: experts[m] for m in s}) for s in proper_subsets(self.modalities)
        ]
        skl = torch.stack(
            [symmetric_kl(q.mu, q.logvar, q_all.mu, q_all.logvar).mean() for q in subset_posteriors]
        ).mean()
        terms["subset_skl"] = skl
        terms["loss"] = loss + self.delta * self.kl_scale * skl
        return terms

    def _mode_seeking(self, experts, codes, labels, terms) -> torch.Tensor:
        """Winner-takes-all reconstruction from the label posterior's mean: for each sample,
        the squared distance from d_m(mean of q(c | label)) to the nearest bottom code z_m of a
        sample of the same class, weighted by gamma_m. The candidates are the batch's samples
        of that class (itself included) or, with ``mode_bank`` > 0, the last ``mode_bank``
        codes of that class seen in training, this batch's among them.

        The top decoders are trained by squared error onto z_m, so from the broad label
        posterior they regress to the class's average code, which decodes to a blend of its
        styles. This term asks that mean to decode to one real style instead (a mode, not the
        mean), without touching the joint posterior's reconstruction. With one or two samples
        of a class per batch the nearest of them is nearly a random one, which again pulls
        toward the average; a bank of many offers a real choice, so the target is the style
        nearest to what the decoder already gives, and the decoder bends least."""
        label_mean = self._fuse({"label": experts["label"]}).mu
        total = 0.0
        for m in self.modalities:
            if m == "label":
                continue
            decoded = self.top_decoders[m](label_mean)
            if self.mode_bank:
                if self.training:  # validation never changes what training aims at
                    self.banks[m].store(codes[m], labels)
                nearest = self.banks[m].nearest_distance(decoded, labels).mean()
            else:
                nearest = nearest_same_class(decoded, codes[m], labels).mean()
            terms[f"mode_{m}"] = nearest
            total = total + self.gammas[m] * nearest
        return total

    def importance_path(self, target: str, x_target: torch.Tensor, given: Inputs) -> ImportancePath:
        """Marginal log p(x_m) (``given`` empty) uses the bottom VAE of m (proposal q(z_m | x_m),
        decoder g_m, latent 16). Conditional log p(x_a | x_S): proposal q(c | x_S) from the
        given subset, decoder g_a(d_a(c)), latent 8 (the reference code's estimator)."""
        self.check_cell(target, given)
        if not given:
            mu, logvar = self.encoders[target](x_target)
            return ImportancePath(
                Gaussian(mu, logvar), self.decoders[target], target, self.latent_dim
            )
        return ImportancePath(
            self.encode(given), lambda c: self.decode(c, target), target, self.top_latent_dim
        )
