"""Trained models as MLflow models (prg.serving): logged by every training run, loaded with
``mlflow.pyfunc.load_model``, registered with metrics and a champion alias, and served over HTTP by
the real ``mlflow models serve`` on loopback."""

from __future__ import annotations

import json
import os
import socket
import subprocess
import sys
import time
import urllib.error
import urllib.request
from pathlib import Path

import numpy as np
import pytest
from mlflow import MlflowClient

from prg.commands.serving import main
from prg.serving import CHAMPION
from tests.helpers.serving import _train_muse, library_rollout, trained  # noqa: F401 (fixtures)

BIN = Path(sys.executable).parent


def test_register_tags_metrics_and_moves_the_champion_alias(trained, tmp_path, small_dataset):
    second = _train_muse(trained["root"], small_dataset, seed=1)  # another run, same store
    exports = {
        trained["run_id"]: trained["root"] / "models" / "muse",
        second.run_id: trained["root"] / "models" / "muse-1",
    }
    client = MlflowClient(trained["uri"])

    def register(run_id: str, coherence: float) -> str:
        evaluation = tmp_path / f"{run_id}.json"
        evaluation.write_text(json.dumps({"muse/coherence_folded_T_given_S": coherence}))
        args = ["register", str(exports[run_id]), "--evaluation", str(evaluation)]
        args += ["--name", "prg-muse-reg", "--tracking-uri", trained["uri"]]
        # a process of its own: MLflow's global tracking URI is not this test's
        done = subprocess.run(
            [sys.executable, "-m", "prg.commands.serving", *args], capture_output=True, text=True
        )
        assert done.returncode == 0, done.stdout + done.stderr[-3000:]
        assert done.stdout.strip().startswith("registered prg-muse-reg version")
        (version,) = [
            v for v in client.search_model_versions("name = 'prg-muse-reg'") if v.run_id == run_id
        ]
        return version.version

    first = register(trained["run_id"], 0.81)
    better = register(second.run_id, 0.93)
    champion = client.get_model_version_by_alias("prg-muse-reg", CHAMPION)
    assert champion.version == better != first  # the best coherence
    assert champion.tags["metric.coherence_folded_T_given_S"] == "0.93"
    assert float(champion.tags["metric.val_loss"]) == pytest.approx(
        json.loads((exports[second.run_id] / "metrics.json").read_text())["val_loss"], rel=1e-5
    )
    # the first run evaluated again: its version is updated, not duplicated, and now wins
    assert register(trained["run_id"], 0.97) == first
    assert len(client.search_model_versions("name = 'prg-muse-reg'")) == 2
    assert client.get_model_version_by_alias("prg-muse-reg", CHAMPION).version == first


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def test_a_registered_version_is_served_over_http(trained, tmp_path):
    export = trained["root"] / "models" / "muse"
    assert (
        main(["register", str(export), "--name", "prg-muse-http", "--tracking-uri", trained["uri"]])
        == 0
    )
    port = _free_port()
    # the server runs `uvicorn` by name: this environment's bin first, as an activated venv has it
    path = f"{BIN}{os.pathsep}{os.environ.get('PATH', '')}"
    env = {**os.environ, "PATH": path, "MLFLOW_TRACKING_URI": trained["uri"]}
    server = subprocess.Popen(
        [
            str(BIN / "mlflow"),
            "models",
            "serve",
            "-m",
            f"models:/prg-muse-http@{CHAMPION}",
            "--env-manager",
            "local",
            "-h",
            "127.0.0.1",
            "-p",
            str(port),
        ],
        env=env,
        cwd=tmp_path,
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
    )
    try:
        base = f"http://127.0.0.1:{port}"
        deadline = time.monotonic() + 180
        while True:
            try:
                with urllib.request.urlopen(f"{base}/ping", timeout=2) as reply:
                    if reply.status == 200:
                        break
            except (urllib.error.URLError, ConnectionError, TimeoutError):
                pass
            assert server.poll() is None, server.stdout.read()[-3000:]
            assert time.monotonic() < deadline, "the model server did not start in 180 s"
            time.sleep(0.5)
        body = json.dumps({"dataframe_records": [{"text": "cat"}]}).encode()
        request = urllib.request.Request(
            f"{base}/invocations", data=body, headers={"Content-Type": "application/json"}
        )
        with urllib.request.urlopen(request, timeout=120) as reply:
            (prediction,) = json.loads(reply.read())["predictions"]
    finally:
        server.terminate()
        server.wait(timeout=30)
    assert prediction["text"] == "cat"
    expected = library_rollout(trained["ckpt"], text="cat")
    assert np.allclose(np.array(json.loads(prediction["rollout"])), expected, atol=1e-5)
