"""prg.resources.project_path: how the reports name a project's files."""

from __future__ import annotations

from prg.resources import project_path


def test_a_file_inside_the_root_is_named_from_it(tmp_path):
    assert project_path(tmp_path / "models/muse/model.ckpt", tmp_path) == "models/muse/model.ckpt"
    assert project_path(tmp_path / "models/x/../muse/m.ckpt", tmp_path) == "models/muse/m.ckpt"
    assert project_path(tmp_path, tmp_path) == "."


def test_a_file_outside_the_root_keeps_its_absolute_path(tmp_path):
    root = tmp_path / "project"
    assert project_path(tmp_path / "elsewhere/a.ckpt", root) == str(tmp_path / "elsewhere/a.ckpt")


def test_a_root_reached_through_a_link(tmp_path):
    real = tmp_path / "real"
    (real / "models").mkdir(parents=True)
    (real / "models" / "a.ckpt").write_text("")
    link = tmp_path / "link"
    link.symlink_to(real)
    assert project_path(real / "models" / "a.ckpt", link) == "models/a.ckpt"
    assert project_path(link / "models" / "a.ckpt", real) == "models/a.ckpt"
