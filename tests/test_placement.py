"""The device a torch model runs on follows its inputs (mi_voldis/tasks/placement.py), tested with plain
objects in place of torch tensors and devices (torch need not be installed)."""
from types import SimpleNamespace

import pytest

from mi_voldis.tasks.placement import device_of, follow


class Tensor:
    """Stands for a torch tensor or module: a device, and ``to`` that returns a copy there."""

    def __init__(self, device, moves=0):
        self.device, self.moves = device, moves

    def to(self, device):
        return Tensor(device, self.moves + 1)


def test_device_of_the_inputs():
    assert device_of([Tensor("cuda:0"), Tensor("cuda:0")]) == "cuda:0"
    with pytest.raises(ValueError, match=r"2 devices \(cpu, cuda:0\)"):
        device_of([Tensor("cuda:0"), Tensor("cpu")])


def test_the_model_moves_once_to_its_inputs_device_and_back():
    """CUDA tensors from Dr.Jit move a CPU-loaded model and its constants there, once; CPU inputs
    later move them back; what is not named stays."""
    guide = SimpleNamespace(device="cpu", model=Tensor("cpu"), text=Tensor("cpu"), other=Tensor("cpu"))
    names = ("model", "text")
    for _ in range(3):
        assert follow(guide, names, device_of([Tensor("cuda:0")] * 3)) == "cuda:0"
    assert guide.device == "cuda:0"
    assert [(guide.model.device, guide.model.moves), (guide.text.device, guide.text.moves)] == [("cuda:0", 1)] * 2
    assert guide.other.device == "cpu" and guide.other.moves == 0
    follow(guide, names, "cpu")
    assert (guide.device, guide.model.device, guide.model.moves) == ("cpu", "cpu", 2)
