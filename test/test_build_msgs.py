"""tools/build_msgs.py builds every interface of msg_defs/ - messages and services."""
from __future__ import annotations

import importlib.util

from conftest import REPO_ROOT


def _build_msgs():
    spec = importlib.util.spec_from_file_location("build_msgs", REPO_ROOT / "tools" /
                                                  "build_msgs.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_every_message_and_service_is_listed_built_and_importable(tmp_path, monkeypatch):
    build_msgs = _build_msgs()
    found = build_msgs.interfaces()
    assert "ChangeModel" in found["srv"] and "ModelVersion" in found["msg"]
    assert build_msgs.unlisted() == []
    assert build_msgs.importable()
    from mt_accuracy_msgs.srv import ChangeModel

    assert list(ChangeModel.Request.get_fields_and_field_types()) == [
        "model", "remove_effects", "add_effects", "refit_effects"]
    assert ChangeModel.Response.get_fields_and_field_types() == {
        "accepted": "boolean", "reason": "string", "version": "uint32"}
    # An interface file CMakeLists.txt does not list would never be generated: named.
    source = tmp_path / "msg_defs"
    (source / "srv").mkdir(parents=True)
    (source / "srv" / "Forgotten.srv").write_text("---\nbool ok\n")
    (source / "CMakeLists.txt").write_text("rosidl_generate_interfaces(x)\n")
    monkeypatch.setattr(build_msgs, "SOURCE", source)
    assert build_msgs.unlisted() == ["srv/Forgotten.srv"]
