"""CLIP guidance (mi_voldis.tasks.clip) on a tiny random CLIP model built offline in a temporary folder."""
import json
import os
import shutil
import string

import pytest

torch = pytest.importorskip("torch", reason="needs PyTorch: pip install .[clip] or .[bench]")
transformers = pytest.importorskip("transformers")

import drjit as dr  # noqa: E402
import mitsuba as mi  # noqa: E402  (variant already selected by conftest's ``import mi_voldis``)
import numpy as np  # noqa: E402

from mi_voldis.losses import semantic_loss  # noqa: E402
from mi_voldis.tasks.clip import ClipGuide  # noqa: E402

PROMPT = "a red chair"
MEAN, STD = (0.5, 0.45, 0.4), (0.25, 0.3, 0.35)
N = 128


@pytest.fixture(scope="module")
def model_dir(tmp_path_factory):
    """A tiny random CLIPModel (seeded), a CLIP BPE tokenizer over lowercase letters and an image
    processor config with non-standard mean/std, all saved with transformers' save_pretrained."""
    root = tmp_path_factory.mktemp("clip")
    path = root / "tiny-clip"
    letters = string.ascii_lowercase
    tokens = [*letters, *(c + "</w>" for c in letters), "re", "red</w>", "<|startoftext|>", "<|endoftext|>"]
    vocab = {t: i for i, t in enumerate(tokens)}
    (root / "vocab.json").write_text(json.dumps(vocab))
    (root / "merges.txt").write_text("#version: 0.2\nr e\nre d</w>\n")
    tokenizer = transformers.CLIPTokenizer(str(root / "vocab.json"), str(root / "merges.txt"))
    tokenizer.save_pretrained(path)
    processor = getattr(transformers, "CLIPImageProcessorPil", None) or transformers.CLIPImageProcessor
    processor(image_mean=list(MEAN), image_std=list(STD)).save_pretrained(path)
    special = dict(bos_token_id=vocab["<|startoftext|>"], eos_token_id=vocab["<|endoftext|>"],
                   pad_token_id=vocab["<|endoftext|>"])
    config = transformers.CLIPConfig(
        text_config=dict(vocab_size=len(vocab), hidden_size=32, intermediate_size=64, num_hidden_layers=2,
                         num_attention_heads=2, max_position_embeddings=77, **special),
        vision_config=dict(image_size=224, patch_size=32, hidden_size=32, intermediate_size=64,
                           num_hidden_layers=2, num_attention_heads=2),
        projection_dim=16)
    torch.manual_seed(0)
    transformers.CLIPModel(config).save_pretrained(path)
    return path


@pytest.fixture(scope="module")
def guide(model_dir):
    return ClipGuide(model_dir, PROMPT, threads=2)


def images(seed=0):
    """Random edited / background images and a square object mask, as mi.TensorXf."""
    rng = np.random.default_rng(seed)
    edited = rng.uniform(0.1, 0.9, (N, N, 3)).astype(np.float32)
    background = rng.uniform(0.1, 0.9, (N, N, 3)).astype(np.float32)
    mask = np.zeros((N, N, 1), np.float32)
    mask[32:96, 40:100] = 1
    return mi.TensorXf(edited), mi.TensorXf(background), mi.TensorXf(mask)


def test_loads_tiny_model(guide, model_dir):
    assert guide.tokenizer(PROMPT)["input_ids"][2] == guide.tokenizer.convert_tokens_to_ids("red</w>")
    assert not any(p.requires_grad for p in guide.model.parameters()) and not guide.model.training
    assert guide.size == 224
    np.testing.assert_allclose(guide.mean.flatten(), MEAN)
    np.testing.assert_allclose(guide.std.flatten(), STD)
    assert torch.linalg.norm(guide.text) == pytest.approx(1.0, abs=1e-5)
    # A 224 x 224 image needs no resampling: compare with transformers' own CLIPModel forward pass.
    image = np.random.default_rng(1).random((224, 224, 3)).astype(np.float32)
    pixels = (torch.from_numpy(image).permute(2, 0, 1)[None] - torch.tensor(MEAN).view(1, 3, 1, 1)) \
        / torch.tensor(STD).view(1, 3, 1, 1)
    tokens = guide.tokenizer([PROMPT], return_tensors="pt")
    with torch.no_grad():
        out = guide.model(input_ids=tokens["input_ids"], pixel_values=pixels)
    reference = float(out.logits_per_image[0, 0] / guide.model.logit_scale.exp())
    assert guide.similarity(image) == pytest.approx(reference, abs=1e-5)
    assert -1.0 <= guide.similarity(image[:N, :N]) <= 1.0


def test_missing_folder(tmp_path):
    missing = tmp_path / "nowhere"
    with pytest.raises(ValueError, match="nowhere"):
        ClipGuide(missing, PROMPT)


def _break(folder, how):
    if how == "empty":
        for name in os.listdir(folder):
            os.remove(folder / name)
    elif how == "wrong_type":
        config = json.loads((folder / "config.json").read_text())
        (folder / "config.json").write_text(json.dumps({**config, "model_type": "bert"}))
    elif how == "no_tokenizer":
        for name in ("tokenizer.json", "vocab.json", "merges.txt"):
            if (folder / name).exists():
                os.remove(folder / name)
    elif how == "bad_tokenizer":
        (folder / "tokenizer.json").write_text("not json")
    elif how == "no_weights":
        os.remove(folder / "model.safetensors")
    elif how == "bad_weights":
        (folder / "model.safetensors").write_bytes(b"\0" * 64)
    elif how == "partial_weights":
        from safetensors.torch import load_file, save_file
        weights = load_file(folder / "model.safetensors")
        save_file({k: v for k, v in weights.items() if not k.startswith("text_model")},
                  folder / "model.safetensors", metadata={"format": "pt"})


@pytest.mark.parametrize("how", ["empty", "wrong_type", "no_tokenizer", "bad_tokenizer", "no_weights",
                                 "bad_weights", "partial_weights"])
def test_not_a_clip_folder(model_dir, tmp_path, how):
    folder = tmp_path / f"broken-{how}"
    shutil.copytree(model_dir, folder)
    _break(folder, how)
    with pytest.raises(ValueError, match=f"broken-{how}"):
        ClipGuide(folder, PROMPT)


def test_loss_gradient(guide):
    """semantic_loss (CLIP text and background terms, and the L2 outside the mask) against finite
    differences, through dr.wrap into torch and back."""
    edited, background, mask = images()
    full, _, _ = images(seed=5)
    dr.enable_grad(edited)
    loss = semantic_loss(guide, edited, background, full, mask, 0.5, 10.0)
    assert isinstance(loss, mi.Float) and dr.width(loss) == 1
    dr.backward(loss)
    grad = dr.grad(edited).numpy()
    inside = mask.numpy()[..., 0] > 0
    assert np.all(np.isfinite(grad))
    assert np.abs(grad[inside]).max() > 0

    def value(image):
        return semantic_loss(guide, mi.TensorXf(image), background, full, mask, 0.5, 10.0)[0]

    base, eps = edited.numpy(), 2e-2
    flat = np.abs(grad).reshape(-1)
    for index in np.argsort(flat)[-2:]:  # the two pixel channels with the largest gradients
        y, x, c = np.unravel_index(index, grad.shape)
        plus, minus = base.copy(), base.copy()
        plus[y, x, c] += eps
        minus[y, x, c] -= eps
        numeric = float(value(plus) - value(minus)) / (2 * eps)
        assert numeric == pytest.approx(grad[y, x, c], rel=0.05, abs=0.02 * float(flat.max()))


def test_the_model_runs_on_the_variants_device(guide):
    """Dr.Jit hands CUDA tensors to CLIP under cuda_ad_rgb: the model follows them there (and NumPy
    images to it), and the terms are those of the CPU model's."""
    composite, background, _ = images(2)
    cpu = [guide.similarity(np.array(t)) for t in (composite, background)]
    guide.cosines(composite, composite, background)
    assert guide.device.type == ("cuda" if mi.variant().startswith("cuda") else "cpu")
    assert next(guide.model.parameters()).device.type == guide.device.type
    assert [guide.similarity(np.array(t)) for t in (composite, background)] == pytest.approx(cpu, abs=1e-5)


def test_descent_raises_similarity(guide):
    """Adam on a 16 x 16 colour parameter (sigmoid, repeated 8 x 8 to 128 x 128) raises the
    similarity of the mask-composited view to the prompt."""
    _, background, mask = images(seed=2)
    m, bg = mask.numpy(), background.numpy()
    y, x, c = np.mgrid[0:N, 0:N, 0:3]
    index = mi.UInt32(((y // 8 * 16 + x // 8) * 3 + c).ravel())
    opt = mi.ad.Adam(lr=0.1)
    opt["raw"] = mi.TensorXf(np.zeros((16, 16, 3), np.float32))

    def edited():
        return mi.TensorXf(dr.gather(mi.Float, dr.rcp(1 + dr.exp(-opt["raw"].array)), index), (N, N, 3))

    def similarity():
        return guide.similarity(m * edited().numpy() + (1 - m) * bg)

    before = similarity()
    for _ in range(8):
        dr.backward(semantic_loss(guide, edited(), background, background, mask, 0.5, 0.0))
        opt.step()
    after = similarity()
    assert after > before + 0.05, (before, after)


def test_semantic_task_end_to_end(model_dir, tiny_run):
    """The real task on a fitted run: loads the model folder, optimises the foreground colour grid
    through render -> CLIP -> dr.wrap -> Dr.Jit, and writes the edit."""
    from mi_voldis.tasks import run_task
    out = run_task(tiny_run, "semantic", {"prompt": PROMPT, "clip_model": str(model_dir), "steps": 12},
                   progress=False)
    m = json.loads(open(os.path.join(out, "metrics.json")).read())
    assert len(json.loads(open(os.path.join(out, "log.json")).read())) == 12
    # each step sees another view: judge on the fixed held-out grids instead of the step losses
    assert m["clip_similarity_after"] > m["clip_similarity_before"], m
    assert os.path.isfile(os.path.join(out, "fg_color_color.vol"))
    with pytest.raises(ValueError, match="nowhere"):
        run_task(tiny_run, "semantic", {"prompt": PROMPT, "clip_model": "/nowhere"}, progress=False)
