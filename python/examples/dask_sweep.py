"""A parameter sweep fanned out with Dask: the paper's pendulum at several mesh sizes, one
task per run, gathering a table of Ĥ(T) against the number of elements.

The local cluster here stands in for a real one: to use a cluster, replace the
`LocalCluster(...)` line by `Client("tcp://scheduler:8786")`."""

import pathlib

from dask.distributed import Client, LocalCluster

ROOT = pathlib.Path(__file__).resolve().parents[2]
PAPER = str(ROOT / "examples" / "paper_pendulum.toml")


def final_hamiltonian(elements: int) -> tuple:
    import phstring  # imported on the worker

    res = phstring.run(phstring.Scenario.from_file(PAPER, set=[f"mesh.elements={elements}"]))
    return elements, float(res.hamiltonian[-1]), float(abs(res.balance_error).max())


if __name__ == "__main__":
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster, Client(cluster) as client:
        futures = client.map(final_hamiltonian, [10, 20, 30, 60, 120])
        rows = sorted(client.gather(futures))
    print("elements,H(T) [J],max |balance error| [J]")
    for n, h, b in rows:
        print(f"{n},{h:.9f},{b:.2e}")
