"""How well the frontier-property UNet does on frontier pixels: the training loss, and the scores on
held-out homes next to a baseline.

The baseline predicts the training median everywhere, so a training history shows whether the
network learned anything beyond the typical value.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import torch

from agent.lfe.model import TARGETS, FrontierUNet, from_network, to_network
from agent.lfe.training_set import Batch


def masked_l1(outputs: torch.Tensor, targets: torch.Tensor, mask: torch.Tensor) -> torch.Tensor:
    """The training loss: the paper's L1, on frontier pixels only.

    Args:
        outputs: the network's outputs (B, 3, C, C).
        targets: the targets in network units (B, 3, C, C).
        mask: the frontier pixels (B, C, C).

    Returns:
        The mean absolute error over frontier pixels and the three channels (network units).
    """
    return (outputs - targets).abs().mean(dim=1)[mask].mean()


@dataclass(frozen=True)
class Validation:
    """The fixed validation crops, evaluated in mini-batches, and the baseline they are compared with.

    Args:
        batches: the crops of the held-out homes, drawn once.
        median: (3,) the training targets' median, in natural units.
    """

    batches: list[Batch]
    median: torch.Tensor

    def evaluate(self, model: FrontierUNet, device: torch.device) -> dict[str, Any]:
        """Score ``model`` on the validation crops.

        Args:
            model: the network, left in eval mode.
            device: where it runs.

        Returns:
            ``val_loss``, the L1 in network units, and ``val_mae``, the MAE per channel in natural units.
        """
        model.eval()
        with torch.inference_mode():
            outputs = [model(batch.inputs.to(device)).cpu() for batch in self.batches]
        return self._score(outputs)

    def baseline(self) -> dict[str, Any]:
        """Score the baseline on the validation crops.

        Returns:
            The scores of `evaluate` for predicting the training median at every pixel.
        """
        constant = to_network(self.median)[None, :, None, None]
        return self._score([constant.expand_as(batch.targets) for batch in self.batches])

    def _score(self, outputs: list[torch.Tensor]) -> dict[str, Any]:
        picked = [(out.permute(0, 2, 3, 1)[b.mask], b.targets.permute(0, 2, 3, 1)[b.mask])
                  for out, b in zip(outputs, self.batches)]
        predicted, wanted = (torch.cat(part) for part in zip(*picked))
        mae = (from_network(predicted) - torch.expm1(wanted)).abs().mean(dim=0)
        return {"val_loss": float((predicted - wanted).abs().mean()),
                "val_mae": {name: float(v) for name, v in zip(TARGETS, mae)}}
