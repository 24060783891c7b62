"""Builds the piezoid package; the protobuf bindings are generated from the project's proto/ at build time.

`pip install ./python` (from the checkout) runs protoc on ../proto/*.proto into piezoid/_proto/, so the
Python client always speaks the wire contract of the checkout it was built from.
"""
import pathlib
import re
import shutil
import subprocess

from setuptools import setup
from setuptools.command.build_py import build_py

HERE = pathlib.Path(__file__).resolve().parent
PROTO_DIR = HERE.parent / "proto"


class BuildWithProtos(build_py):
    def run(self):
        protos = sorted(PROTO_DIR.glob("*.proto"))
        if not protos:
            raise SystemExit(f"piezoid: no .proto files in {PROTO_DIR}: build from a piezoid checkout")
        protoc = shutil.which("protoc")
        if protoc is None:
            raise SystemExit("piezoid: protoc not found: install protobuf-compiler (scripts/deps.sh)")
        out = HERE / "piezoid" / "_proto"
        out.mkdir(exist_ok=True)
        subprocess.run([protoc, f"-I{PROTO_DIR}", f"--python_out={out}", *map(str, protos)], check=True)
        # The generated modules import each other at top level ("import job_pb2"): make that relative.
        for gen in out.glob("*_pb2.py"):
            text = gen.read_text()
            text = re.sub(r"^import (\w+_pb2) as", r"from . import \1 as", text, flags=re.M)
            gen.write_text(text)
        
        super().run()


setup(cmdclass={"build_py": BuildWithProtos})
