import pytest
import torch

from centerart.utils.torch_cpu import flush_denormals, use_cpu_threads

DENORMAL = 1e-39  # below float32's smallest normal number, 1.18e-38


def test_use_cpu_threads_reads_denormals_as_zero_and_sets_threads():
    before = torch.get_num_threads()
    try:
        use_cpu_threads(1)
        if not flush_denormals():
            pytest.skip("this CPU cannot flush denormals (no SSE3)")
        assert torch.get_num_threads() == 1
        x = torch.tensor([DENORMAL, 1.0], dtype=torch.float32)
        assert (x * 1.0).tolist() == [0.0, 1.0]
        use_cpu_threads(0)  # 0 keeps the thread count
        assert torch.get_num_threads() == 1
    finally:
        torch.set_flush_denormal(False)
        torch.set_num_threads(before)
    assert (torch.tensor([DENORMAL]) * 1.0).item() > 0  # the default again: denormals kept
