"""Which model files the reader is built from: the shipped ones, or a candidate folder."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from gauged.config.model import ReaderConfig
from gauged.reader.factory import (
    CROP_MODEL,
    DETECTOR_MODEL,
    NUMBER_NET_MODEL,
    build_reader,
    helper_model_path,
    model_path,
)
from gauged.reader.onnx_model import ModelNotAvailable, packaged_model_path


def test_model_path_is_the_shipped_file_without_a_folder():
    assert model_path(CROP_MODEL) == packaged_model_path(CROP_MODEL)
    assert model_path(DETECTOR_MODEL, Path("/x")) == Path("/x") / DETECTOR_MODEL


def test_build_reader_from_an_empty_candidate_folder_names_the_missing_file(tmp_path):
    with pytest.raises(ModelNotAvailable, match=str(tmp_path / CROP_MODEL)):
        build_reader(ReaderConfig(threads=1, models_dir=tmp_path))


@pytest.mark.skipif(not packaged_model_path(CROP_MODEL).is_file(), reason="gauged/models/crop.onnx is not shipped")
def test_build_reader_uses_the_candidate_folder(tmp_path):
    shutil.copy(packaged_model_path(CROP_MODEL), tmp_path / CROP_MODEL)
    reader = build_reader(ReaderConfig(threads=1, models_dir=tmp_path))
    assert reader.crop_model.path == tmp_path / CROP_MODEL
    assert reader.detector is None  # no detector.onnx in the folder: photos are read as one gauge


def test_the_ocr_models_come_from_the_candidate_folder_only_where_it_holds_them(tmp_path):
    assert helper_model_path(NUMBER_NET_MODEL, tmp_path) == packaged_model_path(NUMBER_NET_MODEL)
    assert helper_model_path(NUMBER_NET_MODEL) == packaged_model_path(NUMBER_NET_MODEL)
    (tmp_path / NUMBER_NET_MODEL).write_bytes(b"")
    assert helper_model_path(NUMBER_NET_MODEL, tmp_path) == tmp_path / NUMBER_NET_MODEL


@pytest.mark.skipif(not (packaged_model_path(CROP_MODEL).is_file() and packaged_model_path(NUMBER_NET_MODEL).is_file()),
                    reason="gauged/models/crop.onnx or numbers.onnx is not shipped")
def test_build_reader_takes_a_candidate_number_net(tmp_path):
    shutil.copy(packaged_model_path(CROP_MODEL), tmp_path / CROP_MODEL)
    shutil.copy(packaged_model_path(NUMBER_NET_MODEL), tmp_path / NUMBER_NET_MODEL)
    reader = build_reader(ReaderConfig(threads=1, models_dir=tmp_path))
    if reader.ocr is None:
        pytest.skip("no OCR wheel installed")
    assert reader.ocr.engine.number_net.path == tmp_path / NUMBER_NET_MODEL
