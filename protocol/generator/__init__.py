"""The PocketBot protocol generator: protocol/pocketbot.toml -> a model -> one emitter per output.

Each emitter module names its output path(s) and returns {path relative to the repository: text or bytes}."""
import tomllib
from pathlib import Path

from . import c_code, c_golden, docs, fuzz_seeds, golden, javolution, kotlin_codecs, kotlin_golden, sdk_model, sdk_settings
from .model import Model


def load(schema_path):
    return Model(tomllib.loads(Path(schema_path).read_text()))


def generate(model):
    vectors = golden.vectors(model)
    outputs = {}
    for part in (c_code.emit(model), c_golden.emit(model, vectors), kotlin_codecs.emit(model),
                 kotlin_golden.emit(model, vectors), javolution.emit(model, vectors), docs.emit(model),
                 golden.emit(model, vectors), fuzz_seeds.emit(model, vectors), sdk_settings.emit(model),
                 sdk_model.emit(model)):
        assert not set(part) & set(outputs), "two emitters write the same file"
        outputs.update(part)
    return outputs
