"""CLIP guidance for text-driven colour edits (Benaim et al. 2022, Sec. 3.3; the loss itself is
:func:`mi_voldis.losses.semantic_loss`).

A rendered image ``I`` (H x W x 3, display-encoded in [0, 1]; 128 x 128 in the paper) enters CLIP as

    x = (up(I) - mu) / s,

``up`` the bilinear upsampling to CLIP's input size S x S (S = 224 for the paper's ViT-B models; taken
from the model's vision config) and ``mu``, ``s`` the per-channel mean and standard deviation of the
folder's image-processor config (the standard CLIP values when it has none). The image embedding
``E_I(I)`` is the visual projection of the vision transformer's pooled output, the text embedding
``E_T(p)`` the text projection of the text transformer's pooled output, both L2-normalised, so the
cosine similarity is their dot product.

Needs ``torch`` and ``transformers`` (imported here only, so the rest of the package runs without
them) and a local Hugging Face CLIP folder: nothing is downloaded.
"""
import json
import os

import drjit as dr
import mitsuba as mi
import numpy as np
import torch
import torch.nn.functional as F
from transformers import AutoTokenizer, CLIPModel

from .placement import device_of, follow

CLIP_MEAN = (0.48145466, 0.4578275, 0.40821073)
CLIP_STD = (0.26862954, 0.26130258, 0.27577711)


def _read_json(path):
    with open(path) as f:
        return json.load(f)


def image_normalisation(model_dir):
    """CLIP's per-channel (mean, std): from ``preprocessor_config.json`` or the ``image_processor`` of
    ``processor_config.json`` in ``model_dir`` when present, else the standard CLIP values."""
    for name, key in (("preprocessor_config.json", None), ("processor_config.json", "image_processor")):
        path = os.path.join(model_dir, name)
        if os.path.isfile(path):
            config = _read_json(path)
            config = config.get(key, {}) if key else config
            if "image_mean" in config and "image_std" in config:
                return tuple(config["image_mean"]), tuple(config["image_std"])
    return CLIP_MEAN, CLIP_STD


def _check_folder(model_dir):
    """Raise ``ValueError`` naming ``model_dir`` unless it looks like a local CLIP model folder."""
    if not os.path.isdir(model_dir):
        raise ValueError(f"{model_dir}: no such CLIP model folder")
    config = os.path.join(model_dir, "config.json")
    if not os.path.isfile(config):
        raise ValueError(f"{model_dir}: not a CLIP model folder (no config.json)")
    try:
        model_type = _read_json(config).get("model_type")
    except (OSError, ValueError) as e:
        raise ValueError(f"{model_dir}: config.json cannot be read ({e})") from None
    if model_type != "clip":
        raise ValueError(f"{model_dir}: not a CLIP model (config.json has model_type {model_type!r}, "
                         f"expected 'clip')")
    files = set(os.listdir(model_dir))
    if "tokenizer.json" not in files and not {"vocab.json", "merges.txt"} <= files:
        raise ValueError(f"{model_dir}: CLIP tokenizer files missing (need tokenizer.json, or vocab.json "
                         f"and merges.txt)")


class ClipGuide:
    """A frozen CLIP model from the local folder ``model_dir`` and the embedding of ``prompt``.

    ``threads`` sets torch's intra-op thread count (process-wide). Raises ``ValueError`` naming the folder
    when it is missing or not a loadable CLIP model. The model runs on the device of the images it is
    given (moved there once, :mod:`mi_voldis.tasks.placement`); NumPy images go to where it is.
    """

    MOVED = ("model", "mean", "std", "text")  # what runs on the inputs' device

    def __init__(self, model_dir, prompt, threads=None):
        model_dir = os.fspath(model_dir)
        _check_folder(model_dir)
        if threads:
            torch.set_num_threads(int(threads))
        try:
            self.tokenizer = AutoTokenizer.from_pretrained(model_dir, local_files_only=True)
        except Exception as e:  # transformers raises OSError, ValueError, TypeError, ... by cause
            raise ValueError(f"{model_dir}: the CLIP tokenizer cannot be loaded ({e})") from None
        try:
            model, info = CLIPModel.from_pretrained(model_dir, local_files_only=True, output_loading_info=True)
        except Exception as e:
            raise ValueError(f"{model_dir}: the CLIP weights cannot be loaded ({e})") from None
        if info["missing_keys"]:
            raise ValueError(f"{model_dir}: the CLIP weights lack {len(info['missing_keys'])} parameters "
                             f"(e.g. {sorted(info['missing_keys'])[0]})")
        self.model = model.eval().requires_grad_(False)
        self.device = torch.device("cpu")
        self.size = int(model.config.vision_config.image_size)
        mean, std = image_normalisation(model_dir)
        self.mean = torch.tensor(mean, dtype=torch.float32).view(1, 3, 1, 1)
        self.std = torch.tensor(std, dtype=torch.float32).view(1, 3, 1, 1)
        tokens = self.tokenizer([prompt], padding=True, truncation=True, return_tensors="pt",
                                max_length=model.config.text_config.max_position_embeddings)
        with torch.no_grad():
            text = model.text_model(input_ids=tokens["input_ids"], attention_mask=tokens["attention_mask"])
            self.text = F.normalize(model.text_projection(text.pooler_output), dim=-1)[0]

    def embed(self, images):
        """L2-normalised ``E_I`` of a torch batch (N, H, W, 3) in [0, 1]: (N, D), on the batch's device."""
        follow(self, self.MOVED, device_of([images]))
        x = F.interpolate(images.permute(0, 3, 1, 2), size=(self.size, self.size), mode="bilinear",
                          align_corners=False)
        pooled = self.model.vision_model(pixel_values=(x - self.mean) / self.std).pooler_output
        return F.normalize(self.model.visual_projection(pooled), dim=-1)

    def similarity(self, image):
        """cos(E_I(image), E_T(prompt)) of a NumPy (H, W, 3) image in [0, 1], as a float."""
        x = torch.from_numpy(np.ascontiguousarray(image, dtype=np.float32))[None].to(self.device)
        with torch.no_grad():
            return float(self.embed(x)[0] @ self.text)

    def cosines(self, composite, edited, background):
        """cos(E_I(composite), E_T(prompt)) and cos(E_I(edited), E_I(background)) as one-element
        ``mi.Float`` each, differentiable w.r.t. ``composite`` and ``edited`` (``mi.TensorXf`` (H, W, 3)
        in [0, 1]): the CLIP terms of :func:`mi_voldis.losses.semantic_loss`. The torch part runs
        under ``dr.wrap``, so ``dr.backward`` reaches the Dr.Jit inputs."""

        @dr.wrap(source="drjit", target="torch")
        def cosines(composite, edited, background):
            e = self.embed(torch.stack((composite, edited, background)))
            return torch.stack((e[0] @ self.text, e[1] @ e[2]))

        values = cosines(composite, edited, dr.detach(background)).array
        return dr.gather(mi.Float, values, mi.UInt32(0)), dr.gather(mi.Float, values, mi.UInt32(1))
