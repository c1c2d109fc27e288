"""Which device a torch model runs on: the one of the tensors it is given.

Under ``dr.wrap``, Dr.Jit hands torch tensors on the device of the active variant (``cuda:0`` with
``cuda_ad_rgb``, the CPU with ``llvm_ad_rgb``); a model that stays where it was loaded then fails on
mixed devices. Torch-free (objects with ``device`` and ``to(device)``), so that it is tested without torch.
"""


def device_of(tensors):
    """The device that all ``tensors`` are on; ``ValueError`` naming the devices when they differ."""
    devices = {str(t.device): t.device for t in tensors}
    if len(devices) != 1:
        raise ValueError(f"inputs on {len(devices)} devices ({', '.join(sorted(devices))}); expected one")
    return next(iter(devices.values()))


def follow(holder, names, device):
    """Move ``holder``'s attributes ``names`` (a model, tensors) to ``device`` unless ``holder.device``
    already is it; record it there. Returns ``device``."""
    if str(device) != str(holder.device):
        for name in names:
            setattr(holder, name, getattr(holder, name).to(device))
        holder.device = device
    return device
