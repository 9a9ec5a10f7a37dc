#!/bin/bash
# The wheels run_device.sh installs on the lent device (which has JAX 0.11.2 but no MuJoCo), built
# here into .whlmin/ (git-ignored through .git/info/exclude): ``bash make_whlmin.sh`` from the
# repository's root, then ``run(carry=[".whlmin"])``. The device copies the working tree and the
# carried paths up to 64e6 bytes in all, and the tracked tree is about 49e6: so mujoco-mjx's wheel
# is rebuilt without its test data (12 MB of meshes), and mujoco-studio (the viewer, 13 MB; `import
# mujoco` does not need it) and tensorboardX (the training logs) are left out. 2026-12-06: 15 MB.
set -e
W=.whlmin
grep -qx "/$W/" .git/info/exclude || echo "/$W/" >> .git/info/exclude
rm -rf $W /tmp/mjx_rebuild && mkdir -p $W /tmp/mjx_rebuild
python3 -m pip download -q --no-deps --only-binary=:all: --python-version 3.12 --implementation cp \
  --platform manylinux_2_28_x86_64 --platform manylinux_2_27_x86_64 --platform manylinux_2_17_x86_64 \
  --platform manylinux2014_x86_64 -d $W mujoco==4.0.0 mujoco-core==4.0.0 mujoco-mjx==3.17.0 glfw pyopengl \
  evosax dotmap trimesh
(cd /tmp/mjx_rebuild && unzip -q "$OLDPWD"/$W/mujoco_mjx-*.whl && rm -rf mujoco/mjx/test_data \
  && sed -i '/^mujoco\/mjx\/test_data\//d' *.dist-info/RECORD && rm "$OLDPWD"/$W/mujoco_mjx-*.whl \
  && zip -q -r -9 "$OLDPWD"/$W/mujoco_mjx-3.17.0-py3-none-any.whl .)
du -sh $W
