"""The models: the appendix encoders and decoders, the modality registry, likelihoods, the product
of experts, the CVAE, AVAE and MUSE families, the one LightningModule and checkpoint loading."""
