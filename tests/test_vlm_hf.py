"""The `hf` VLM backend on a tiny, randomly initialised LLaVA built and saved here: nothing downloaded."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("transformers", reason="the hf backend needs transformers: pip install -e '.[test]'")

import torch  # noqa: E402
from tokenizers import Tokenizer, decoders, models, pre_tokenizers, trainers  # noqa: E402
from transformers import (  # noqa: E402
    CLIPVisionConfig,
    LlamaConfig,
    LlavaConfig,
    LlavaForConditionalGeneration,
    LlavaProcessor,
    PreTrainedTokenizerFast,
)

from agent.mapping.camera import Intrinsics  # noqa: E402
from agent.observation import Observation  # noqa: E402
from agent.vlm.errors import VLMError  # noqa: E402
from agent.vlm.hf_backend import HuggingFaceVLM  # noqa: E402
from agent.vlm.protocol import VisualQuery  # noqa: E402
from agent.vlm.settings import HFSettings  # noqa: E402

try:  # transformers 5 names the Pillow processor so; CLIPImageProcessor would want torchvision
    from transformers import CLIPImageProcessorPil as ImageProcessor
except ImportError:
    from transformers import CLIPImageProcessor as ImageProcessor

SPECIAL = ["<pad>", "<s>", "</s>", "<unk>", "<image>"]
# Byte-level BPE learns a token for every word here: "A" and " A" (as "ĠA") are both single tokens,
# "Yes" is one but " Yes" is two, "Maybe" is spelt letter by letter. Real tokenizers mix the same way.
CORPUS = ["USER: Which direction? Answer with a single letter. ASSISTANT: A B C D", "Yes No A B C D"]
CHAT_TEMPLATE = (
    "{% for message in messages %}{{ message['role'].upper() + ': ' }}"
    "{% for item in message['content'] %}{% if item['type'] == 'image' %}{{ '<image> ' }}"
    "{% elif item['type'] == 'text' %}{{ item['text'] + ' ' }}{% endif %}{% endfor %}{% endfor %}"
    "{% if add_generation_prompt %}{{ 'ASSISTANT:' }}{% endif %}"
)
IMAGE_SIZE, PATCH = 16, 8
H, W = 24, 32
PROMPT = "Which direction? Answer with a single letter."


def save_tiny_llava(folder: Path) -> None:
    """A LLaVA small enough to build in a second: 2-layer CLIP and Llama of width 16, a BPE tokenizer."""
    tokenizer = Tokenizer(models.BPE())
    tokenizer.pre_tokenizer = pre_tokenizers.ByteLevel(add_prefix_space=False)
    tokenizer.decoder = decoders.ByteLevel()
    tokenizer.train_from_iterator(CORPUS, trainers.BpeTrainer(
        vocab_size=1000, special_tokens=SPECIAL, initial_alphabet=pre_tokenizers.ByteLevel.alphabet(),
        show_progress=False))
    fast = PreTrainedTokenizerFast(tokenizer_object=tokenizer, bos_token="<s>", eos_token="</s>",
                                   unk_token="<unk>", pad_token="<pad>")
    vocab = fast.get_vocab()
    image_processor = ImageProcessor(size={"shortest_edge": IMAGE_SIZE},
                                     crop_size={"height": IMAGE_SIZE, "width": IMAGE_SIZE})
    # One feature per patch once the CLS token is dropped ("default"): the prompt's <image> becomes 4.
    processor = LlavaProcessor(image_processor=image_processor, tokenizer=fast, patch_size=PATCH,
                               num_additional_image_tokens=1, vision_feature_select_strategy="default",
                               chat_template=CHAT_TEMPLATE)
    config = LlavaConfig(
        vision_config=CLIPVisionConfig(hidden_size=16, intermediate_size=32, num_hidden_layers=2,
                                       num_attention_heads=2, image_size=IMAGE_SIZE, patch_size=PATCH),
        text_config=LlamaConfig(vocab_size=len(vocab), hidden_size=16, intermediate_size=32, num_hidden_layers=2,
                                num_attention_heads=2, num_key_value_heads=2, max_position_embeddings=64,
                                initializer_range=0.5, pad_token_id=0, bos_token_id=1, eos_token_id=2),
        image_token_index=vocab["<image>"],
        image_seq_length=(IMAGE_SIZE // PATCH) ** 2,
        vision_feature_layer=-1,
    )
    torch.manual_seed(0)
    LlavaForConditionalGeneration(config).save_pretrained(folder)
    processor.save_pretrained(folder)


@pytest.fixture(scope="module")
def vlm(tmp_path_factory: pytest.TempPathFactory) -> HuggingFaceVLM:
    folder = tmp_path_factory.mktemp("tiny-llava")
    save_tiny_llava(folder)
    return HuggingFaceVLM(HFSettings(path=str(folder), device="cpu"))


def query(seed: int, candidates: tuple[str, ...] = ("A", "B", "C", "D")) -> VisualQuery:
    rgb = np.random.default_rng(seed).integers(0, 256, (H, W, 3), dtype=np.uint8)
    observation = Observation(rgb, np.ones((H, W), np.float32), np.full((H, W), -1, np.int32), (),
                              Intrinsics(W, H, 16.0, 16.0, 16.0, 12.0), np.eye(4), (0.0, 0.0, 0.0))
    return VisualQuery(observation, PROMPT, candidates, {"A": (8.0, 12.0), "B": (24.0, 12.0)})


def test_probabilities_are_normalised_and_deterministic(vlm: HuggingFaceVLM) -> None:
    probs = vlm.probabilities(query(0))
    assert list(probs) == ["A", "B", "C", "D"]
    assert sum(probs.values()) == pytest.approx(1.0)
    assert all(0.0 < p < 1.0 for p in probs.values())
    assert vlm.probabilities(query(0)) == probs
    yes_no = vlm.probabilities(query(0, ("Yes", "No")))
    assert sum(yes_no.values()) == pytest.approx(1.0)


def test_the_image_reaches_the_model(vlm: HuggingFaceVLM) -> None:
    first = np.array(list(vlm.probabilities(query(0)).values()))
    second = np.array(list(vlm.probabilities(query(1)).values()))
    assert np.abs(first - second).max() > 1e-4


def test_a_candidate_that_is_not_one_token_is_named(vlm: HuggingFaceVLM) -> None:
    with pytest.raises(VLMError, match=r"'Maybe' is not a single token.*\['M', 'a', 'y', 'b', 'e'\]"):
        vlm.probabilities(query(0, ("Yes", "Maybe")))
    with pytest.raises(VLMError, match=r"'A B' is not a single token.*\['A', 'ĠB'\]"):
        vlm.probabilities(query(0, ("A B", "C")))


def test_every_single_token_spelling_of_a_candidate_counts(vlm: HuggingFaceVLM, monkeypatch: pytest.MonkeyPatch) -> None:
    """P(A) gathers "A" and " A"; "Yes" has only its bare spelling, " Yes" being two tokens."""
    token_id = vlm.tokenizer.convert_tokens_to_ids
    logits = torch.full((len(vlm.tokenizer),), -5.0)
    for token, logit in {"A": 1.0, "ĠA": 2.0, "B": 0.5, "ĠB": -1.0, "Yes": 0.3, "Ġ": 4.0, "No": 0.0, "ĠNo": 0.0}.items():
        logits[token_id(token)] = logit
    monkeypatch.setattr(vlm, "_next_token_logits", lambda query: logits)
    a, b = np.exp(1.0) + np.exp(2.0), np.exp(0.5) + np.exp(-1.0)
    assert vlm.probabilities(query(0, ("A", "B"))) == pytest.approx({"A": a / (a + b), "B": b / (a + b)})
    yes, no = np.exp(0.3), 2 * np.exp(0.0)
    assert vlm.probabilities(query(0, ("Yes", "No"))) == pytest.approx({"Yes": yes / (yes + no), "No": no / (yes + no)})


def test_a_folder_without_a_model_is_a_clear_error(tmp_path: Path) -> None:
    with pytest.raises(VLMError, match="holds no Hugging Face model"):
        HuggingFaceVLM(HFSettings(path=str(tmp_path)))
    with pytest.raises(VLMError, match="not a folder"):
        HuggingFaceVLM(HFSettings(path=str(tmp_path / "llava-1.5-7b-hf")))
    with pytest.raises(VLMError, match="vlm.hf.path"):
        HuggingFaceVLM(HFSettings())


def test_a_model_without_its_weights_is_a_clear_error(tmp_path: Path) -> None:
    save_tiny_llava(tmp_path)
    (tmp_path / "model.safetensors").unlink()
    with pytest.raises(VLMError, match=f"could not load .* from {tmp_path}"):
        HuggingFaceVLM(HFSettings(path=str(tmp_path), device="cpu"))
