"""A real Dask cluster on 127.0.0.1 for a test: a scheduler and named single-threaded workers,
each a separate process (free ports chosen by the system, announced through a scheduler file),
all stopped when the test ends, also when it fails; on plain TCP or, with the certificates of
:func:`make_certificates`, on Dask's TLS (``tls://``, every party authenticated by a
certificate of the test's own certificate authority)."""
from __future__ import annotations

import contextlib
import json
import os
import subprocess
import sys
import time
from pathlib import Path

from tests.conftest import REPO_ROOT

#: Seconds to wait for the cluster to come up.
STARTUP_S = 120


def dask_command(*args: str, prelude: str = "") -> list[str]:
    """``dask ...`` run by this interpreter (the ``dask`` script of its environment), after the
    Python statements ``prelude``."""
    return [sys.executable, "-c", f"{prelude}import sys; from dask.__main__ import main; sys.exit(main())", *args]


def wait_for(condition, timeout: float, what: str, processes=()) -> None:
    deadline = time.monotonic() + timeout
    while not condition():
        for p in processes:
            assert p.poll() is None, f"{what}: a process ended early ({p.args[-1]})"
        assert time.monotonic() < deadline, f"timed out waiting for {what}"
        time.sleep(0.1)


def make_certificates(folder: Path, name: str = "mocap-test") -> dict[str, Path]:
    """A certificate authority and one certificate it signs for ``127.0.0.1`` and ``localhost``
    (for the scheduler, the workers and the client alike), PEM files in ``folder``, made with the
    ``cryptography`` package: ``{"ca": ..., "cert": ..., "key": ...}``."""
    import datetime
    import ipaddress

    from cryptography import x509
    from cryptography.hazmat.primitives import hashes, serialization
    from cryptography.hazmat.primitives.asymmetric import ec
    from cryptography.x509.oid import NameOID

    now = datetime.datetime.now(datetime.timezone.utc)
    valid = dict(not_valid_before=now - datetime.timedelta(minutes=5), not_valid_after=now + datetime.timedelta(days=1))

    def certificate(subject: str, key, issuer: str, issuer_key, *, ca: bool):
        builder = x509.CertificateBuilder(
            subject_name=x509.Name([x509.NameAttribute(NameOID.COMMON_NAME, subject)]),
            issuer_name=x509.Name([x509.NameAttribute(NameOID.COMMON_NAME, issuer)]),
            public_key=key.public_key(), serial_number=x509.random_serial_number(), **valid)
        builder = builder.add_extension(x509.BasicConstraints(ca=ca, path_length=None), critical=True)
        if not ca:
            builder = builder.add_extension(x509.SubjectAlternativeName(
                [x509.DNSName("localhost"), x509.IPAddress(ipaddress.ip_address("127.0.0.1"))]), critical=False)
        return builder.sign(issuer_key, hashes.SHA256())

    ca_key, key = ec.generate_private_key(ec.SECP256R1()), ec.generate_private_key(ec.SECP256R1())
    ca = certificate(f"{name} CA", ca_key, f"{name} CA", ca_key, ca=True)
    cert = certificate(name, key, f"{name} CA", ca_key, ca=False)
    files = {"ca": folder / f"{name}-ca.pem", "cert": folder / f"{name}.pem", "key": folder / f"{name}-key.pem"}
    files["ca"].write_bytes(ca.public_bytes(serialization.Encoding.PEM))
    files["cert"].write_bytes(cert.public_bytes(serialization.Encoding.PEM))
    files["key"].write_bytes(key.private_bytes(serialization.Encoding.PEM, serialization.PrivateFormat.PKCS8,
                                               serialization.NoEncryption()))
    return files


def tls_options(certificates: dict[str, Path]) -> list[str]:
    """``dask scheduler`` / ``dask worker`` options for TLS with :func:`make_certificates`' files."""
    return ["--tls-ca-file", str(certificates["ca"]), "--tls-cert", str(certificates["cert"]),
            "--tls-key", str(certificates["key"])]


def tls_client_env(certificates: dict[str, Path]) -> dict[str, str]:
    """A Dask client's TLS credentials as environment variables (Dask's configuration:
    ``distributed.comm.tls.*``), the way ``track-many`` gets them on a cluster."""
    return {"DASK_DISTRIBUTED__COMM__TLS__CA_FILE": str(certificates["ca"]),
            "DASK_DISTRIBUTED__COMM__TLS__CLIENT__CERT": str(certificates["cert"]),
            "DASK_DISTRIBUTED__COMM__TLS__CLIENT__KEY": str(certificates["key"])}


def cluster_env() -> dict[str, str]:
    """The environment of the test's processes: they import this checkout, not an installed copy."""
    return {**os.environ, "PYTHONPATH": str(REPO_ROOT) + os.pathsep + os.environ.get("PYTHONPATH", "")}


@contextlib.contextmanager
def local_cluster(folder: Path, workers: dict[str, dict], certificates: dict[str, Path] | None = None):
    """Start a scheduler and the ``workers`` (name -> ``{"prelude": STATEMENTS, "env": {...},
    "nanny": bool, "preload": MODULE}``, all optional; without ``nanny`` a worker is its own
    process, with it a nanny process watches the worker's) with their logs in ``folder``; yield ``(address, processes)``, ``processes``
    a dict name -> Popen to which the test may add its own; kill whatever still runs at the end.
    With ``certificates`` (:func:`make_certificates`) the cluster speaks TLS only (``tls://``)."""
    scheduler_file = folder / "scheduler.json"
    env = cluster_env()
    logs = {name: open(folder / f"{name}.log", "w") for name in ("scheduler", *workers)}
    processes: dict[str, subprocess.Popen] = {}
    scheduler_file.unlink(missing_ok=True)        # (a folder used before: not its old scheduler's address)
    try:
        processes["scheduler"] = subprocess.Popen(
            dask_command("scheduler", "--host", "127.0.0.1", "--port", "0", "--no-dashboard",
                         "--scheduler-file", str(scheduler_file),
                         *(["--protocol", "tls", *tls_options(certificates)] if certificates else [])),
            cwd=folder, env=env, stdout=logs["scheduler"], stderr=subprocess.STDOUT)
        wait_for(scheduler_file.exists, STARTUP_S, "the scheduler file", processes.values())
        time.sleep(0.2)                          # (written whole: read it once it has settled)
        address = json.loads(scheduler_file.read_text())["address"]
        assert address.startswith(("tls" if certificates else "tcp") + "://127.0.0.1:")
        for name, extra in workers.items():
            processes[name] = subprocess.Popen(
                dask_command("worker", address, "--host", "127.0.0.1", "--nworkers", "1", "--nthreads", "1",
                             *([] if extra.get("nanny") else ["--no-nanny"]),
                             *(["--preload", extra["preload"]] if extra.get("preload") else []),
                             "--no-dashboard", "--memory-limit", "0", "--name", name,
                             *(tls_options(certificates) if certificates else []), prelude=extra.get("prelude", "")),
                cwd=REPO_ROOT, env={**env, **extra.get("env", {})}, stdout=logs[name], stderr=subprocess.STDOUT)
        wait_for(lambda: all("Registered to" in (folder / f"{n}.log").read_text() for n in workers),
                 STARTUP_S, "the workers", processes.values())
        yield address, processes
    finally:
        # a nanny is asked to stop first (SIGTERM: it stops its worker's process, which a SIGKILL
        # of the nanny would leave running); whatever still runs then is killed
        for name, p in processes.items():
            if p.poll() is None and workers.get(name, {}).get("nanny"):
                p.terminate()
                try:
                    p.wait(timeout=30)
                except subprocess.TimeoutExpired:
                    pass
        for p in processes.values():
            if p.poll() is None:
                p.kill()
                p.wait(timeout=30)
        for log in logs.values():
            log.close()
