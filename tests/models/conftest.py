import pytest
import torch

# One intra-op thread: on a shared 2-core machine, torch's default thread pool oversubscribes the cores and
# runs these small workloads about 10x slower (measured).
torch.set_num_threads(1)


@pytest.fixture
def loss_batch():
    """A one-view encoder-loss batch: one object over 2 x 2 cells of a 4 x 6 cell grid (32 x 48 pixels)."""
    h, w = 32, 48
    K = torch.tensor([[50.0, 0, 23.5], [0, 50.0, 15.5], [0, 0, 1]])
    cell_object = torch.full((1, 4, 6), -1, dtype=torch.long)
    cell_object[0, 1:3, 2:4] = 0
    m = 8
    batch = {
        "heatmap": torch.zeros(1, h, w),
        "cell_object": cell_object,
        "cell_weight": (cell_object >= 0).float() * 0.9,
        "K": K[None],
        "rotation": torch.eye(3).expand(1, m, 3, 3).clone(),
        "translation": torch.tensor([0.1, -0.05, 2.0]).expand(1, m, 3).clone(),
        "shape_code": torch.zeros(1, m, 32),
        "shape_code_valid": torch.ones(1, m, dtype=torch.bool),
        "joint_code": torch.full((1, m), 0.5),
        "joint_type": torch.zeros(1, m, dtype=torch.long),
        "axis_direction": torch.tensor([0.0, 1.0, 0.0]).expand(1, m, 3).clone(),
        "axis_point_offset": torch.zeros(1, m, 3),
        "joint_state": torch.full((1, m), 0.3),
    }
    return batch
