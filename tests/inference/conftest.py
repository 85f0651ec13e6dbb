import torch

# One intra-op thread: on a shared 2-core machine, torch's default thread pool oversubscribes the cores and
# runs these small workloads about 10x slower (measured).
torch.set_num_threads(1)
