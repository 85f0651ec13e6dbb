"""Render a :class:`~centerart.scenes.description.SceneDescription` with SAPIEN 3 on CPU (Mesa lavapipe) or GPU.

Per camera view it returns RGB, true depth, instance segmentation per object and per link, and the IR pair of the
stereo depth sensor. Objects are loaded with SAPIEN's URDF loader exactly as the asset defines them
(``loader.scale = obj.scale``, root pose ``world_T_object @ canonical_T_base``, joint values by active-joint name),
so the kinematics are SAPIEN's own. For generated objects the visual meshes are then replaced by the same
geometry with box-projected UV coordinates so that procedural textures (wood grain, brushed metal, paint) map
at a metric scale; real PartNet-Mobility objects keep their own textured visuals.

Frames: camera poses in the description are OpenCV (x right, y down, z forward); SAPIEN cameras look along +x
with z up, so ``world_T_sapien = world_T_opencv @ OPENCV_T_SAPIEN`` (both conventions are written once in
:mod:`centerart.geometry.camera`). SAPIEN samples pixel (u, v) at its centre (u + 0.5, v + 0.5); the principal
point handed to SAPIEN is therefore ``K[:2, 2] + 0.5`` so that rendered images follow OpenCV's convention for
``K`` (pixel centres at integer coordinates).
"""

from __future__ import annotations

import shutil
import tempfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import trimesh

from centerart.assets.articulated_object import ArticulatedObject
from centerart.errors import CenterArtError
from centerart.geometry.camera import OPENCV_T_SAPIEN, Intrinsics
from centerart.geometry.transforms import apply_transform
from centerart.scenes.description import MaterialSpec, SceneDescription, load_scene_object
from centerart.scenes.textures import make_texture
from centerart.scenes.visual_files import loadable_visual

INSTANCE_BACKGROUND = 0
#: Shadow map sizes (texels per side) of point (each cube face) and directional lights for images of at least
#: ``SHADOW_MAP_ROWS`` rows; smaller images get maps shrunk in proportion (:func:`shadow_map_sizes`).
POINT_SHADOW_MAP, DIRECTIONAL_SHADOW_MAP, SHADOW_MAP_ROWS = 1024, 2048, 480


def shadow_map_sizes(image_height: int) -> tuple[int, int]:
    """(point, directional) shadow map sizes for images ``image_height`` rows high: the full sizes from
    ``SHADOW_MAP_ROWS`` rows up, else shrunk with the image (powers of two, at least 256), so a shadow map texel
    covers about as many image pixels as at full size. Why: on the CPU rasteriser the maps' passes cost the same
    at any image size; at 320x240 they were 40 % of the RGB picture (100 -> 75 ms per view with half-size maps,
    pixels changed by 0.36 grey levels on average, 0.2 % of them by more than 8)."""
    if image_height >= SHADOW_MAP_ROWS:
        return POINT_SHADOW_MAP, DIRECTIONAL_SHADOW_MAP
    shrink = 2 ** int(np.ceil(np.log2(SHADOW_MAP_ROWS / max(image_height, 1))))
    return max(POINT_SHADOW_MAP // shrink, 256), max(DIRECTIONAL_SHADOW_MAP // shrink, 256)


@dataclass
class ViewImages:
    """One camera view. Depth is float32 metres along the optical axis (0 where nothing was hit)."""

    rgb: np.ndarray  # (H, W, 3) uint8
    depth: np.ndarray  # (H, W) float32
    instances: np.ndarray  # (H, W) uint8: 0 background/room, k + 1 for scene object k
    links: np.ndarray  # (H, W) uint16: 0 background/room, else a link id (see SceneRenderer.link_ids)
    ir_left: np.ndarray | None = None  # (H, W) float32 in 0..1 (IR camera colour)
    ir_right: np.ndarray | None = None
    ir_left_depth: np.ndarray | None = None  # (H, W) float32 true depth seen by each IR camera
    ir_right_depth: np.ndarray | None = None


def uv_mesh(mesh: trimesh.Trimesh, scale_m: float) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Flat-shaded copy of ``mesh`` with box-projected UVs: each face takes the two coordinates orthogonal to its
    dominant normal axis, divided by ``scale_m`` (so one texture repeat covers ``scale_m`` metres)."""
    tris = mesh.vertices[mesh.faces]  # (F, 3, 3)
    normals = mesh.face_normals
    dominant = np.abs(normals).argmax(1)
    axes = np.array([[1, 2], [0, 2], [0, 1]])[dominant]  # (F, 2): u along the first, v along the second
    uv = np.take_along_axis(tris, np.repeat(axes[:, None, :], 3, 1), axis=2) / max(scale_m, 1e-6)
    # Swap to (second, first) axis: on vertical faces u then follows z and v the horizontal axis; the textures'
    # stripes (wood rings, brush strokes) change with v only, so they run vertically on doors and side panels.
    uv = uv[..., ::-1]
    vertices = tris.reshape(-1, 3).astype(np.float32)
    faces = np.arange(len(vertices), dtype=np.uint32).reshape(-1, 3)
    vnormals = np.repeat(normals, 3, axis=0).astype(np.float32)
    return vertices, faces, vnormals, uv.reshape(-1, 2).astype(np.float32)


class SceneRenderer:
    """Builds SAPIEN scenes from descriptions and renders their views.

    One renderer per process: the first picture compiles shaders (several seconds on CPU); later scenes reuse them.
    ``shader`` is ``default`` (rasterizer) or ``rt`` (path tracer for RGB only; depth, segmentation and IR are
    always rasterised because they must be exact and noise-free).
    """

    def __init__(
        self, shader: str = "default", rt_samples_per_pixel: int = 4, ir_shading: str = "fast", ir_cameras: bool = True
    ):
        try:
            import sapien
        except ImportError as err:  # pragma: no cover - sapien is a hard dependency
            raise CenterArtError(f"SAPIEN is not installed ({err})") from None
        self._sapien = sapien
        if shader not in ("default", "rt"):
            raise CenterArtError(f"unknown shader {shader!r}; choose default or rt")
        self.shader = shader
        if ir_shading not in ("fast", "full"):
            raise CenterArtError(f"unknown IR shading {ir_shading!r}; choose fast or full")
        self.ir_shading = ir_shading
        # Without the stereo sensor (realistic depth not matched from an IR pair) its two cameras, the dot pattern
        # and the projector are not made: 56 ms of a 320x240 kitchen's build.
        self.ir_cameras = ir_cameras
        if shader == "rt":
            sapien.render.set_ray_tracing_samples_per_pixel(int(rt_samples_per_pixel))
            sapien.render.set_ray_tracing_path_depth(4)
            sapien.render.set_ray_tracing_denoiser("none")  # OIDN needs CUDA here
        self._textures: dict[str, object] = {}
        self._visuals: Path | None = None
        self.scene = None
        self.description: SceneDescription | None = None
        self.link_ids: dict[int, tuple[int, str]] = {}
        self._entity_to_link_id: np.ndarray = np.zeros(1, np.uint16)
        self._entity_to_instance: np.ndarray = np.zeros(1, np.uint8)
        self._pattern_key = None
        self._pattern: np.ndarray | None = None  # (H, W, 4) uint8 RGBA, the projector's texture
        self._pattern_grey: np.ndarray | None = None  # (H, W) float32 in 0..1, what fast IR shading samples

    # ------------------------------------------------------------------ building
    def build(self, description: SceneDescription, scene_dir: Path | None = None) -> list[ArticulatedObject]:
        """Create the SAPIEN scene; returns the loaded objects (held states as described)."""
        sapien = self._sapien
        try:
            scene = sapien.Scene()
        except RuntimeError as err:
            raise CenterArtError(
                f"SAPIEN found no Vulkan rendering device ({err}); on CPU install Mesa >= 24 lavapipe "
                "(scripts/setup.sh: apt-get install -t bookworm-backports mesa-vulkan-drivers)"
            ) from None
        self.scene, self.description, self._scene_dir = scene, description, scene_dir
        scene.set_ambient_light(list(description.ambient))
        point_map, directional_map = shadow_map_sizes(description.cameras[0].height if description.cameras else 480)
        for light in description.lights:
            if light.kind == "point":
                scene.add_point_light(
                    light.position, light.color, shadow=light.shadow, shadow_far=12.0, shadow_map_size=point_map
                )
            elif light.kind == "directional":
                scene.add_directional_light(
                    light.direction,
                    light.color,
                    shadow=light.shadow,
                    position=[2.0, 0.0, 1.5],
                    shadow_scale=5.0,
                    shadow_map_size=directional_map,
                )
            elif light.kind == "spot":
                scene.add_spot_light(light.position, light.direction, 1.0, 1.2, light.color, shadow=light.shadow)
            else:
                raise CenterArtError(f"scene {description.scene_id}: unknown light kind {light.kind!r}")
        for box in description.boxes:
            self._add_box(box)
        objects = []
        entity_link: dict[int, tuple[int, str]] = {}
        for k, spec in enumerate(description.objects):
            obj = load_scene_object(spec)
            objects.append(obj)
            art = self._add_object(obj, spec)
            for link in art.links:
                entity_link[link.entity.per_scene_id] = (k, link.name)
        # Dense lookup tables from SAPIEN's per-scene entity id to instance and link id.
        n = max(entity_link, default=0) + 1
        self._entity_to_instance = np.zeros(n, np.uint8)
        self._entity_to_link_id = np.zeros(n, np.uint16)
        self.link_ids = {}
        for i, (eid, (k, link)) in enumerate(sorted(entity_link.items(), key=lambda t: (t[1][0], t[1][1]))):
            self._entity_to_instance[eid] = k + 1
            self._entity_to_link_id[eid] = i + 1
            self.link_ids[i + 1] = (k, link)
        self._make_cameras()
        return objects

    def _texture(self, spec: MaterialSpec):
        if spec.kind in ("glass", "plain"):
            return None
        key = spec.texture or f"{spec.kind}-{spec.seed}-{spec.color}"
        if key not in self._textures:
            sapien = self._sapien
            path = Path(self._scene_dir) / spec.texture if (spec.texture and self._scene_dir) else None
            if path is not None and path.is_file():
                self._textures[key] = sapien.render.RenderTexture2D(str(path), mipmap_levels=4)
            else:
                img = make_texture(spec.kind, tuple(spec.color), spec.seed)
                rgba = np.dstack([img, np.full(img.shape[:2], 255, np.uint8)])
                self._textures[key] = sapien.render.RenderTexture2D(rgba, "R8G8B8A8Unorm", mipmap_levels=4, srgb=True)
        return self._textures[key]

    def _material(self, spec: MaterialSpec):
        sapien = self._sapien
        tex = self._texture(spec)
        color = [1.0, 1.0, 1.0, 1.0] if tex is not None else list(spec.color)
        mat = sapien.render.RenderMaterial(
            base_color=color, roughness=spec.roughness, metallic=spec.metallic, specular=spec.specular
        )
        if tex is not None:
            mat.base_color_texture = tex
        return mat

    def _add_box(self, box) -> None:
        sapien = self._sapien
        mesh = trimesh.creation.box(extents=2.0 * np.asarray(box.half_size))
        pose = np.asarray(box.world_T_box, float)
        # UVs from world coordinates so textures of adjacent boxes line up and keep their metric scale.
        mesh.apply_transform(pose)
        v, f, n, uv = uv_mesh(mesh, box.material.texture_scale_m)
        entity = sapien.Entity()
        entity.name = box.name
        body = sapien.render.RenderBodyComponent()
        body.attach(sapien.render.RenderShapeTriangleMesh(v, f, n, uv, self._material(box.material)))
        entity.add_component(body)
        self.scene.add_entity(entity)

    def _add_object(self, obj: ArticulatedObject, spec):
        sapien = self._sapien
        loader = self.scene.create_urdf_loader()
        loader.fix_root_link = True
        loader.scale = obj.scale
        urdf = obj.path / "mobility.urdf"
        builders, actors, _ = loader.parse(str(urdf))
        if len(builders) != 1 or actors:
            raise CenterArtError(f"{urdf}: SAPIEN found {len(builders)} articulations and {len(actors)} free bodies")
        if spec.materials:
            # Re-dressed below with the scene's materials: SAPIEN's own visual meshes would be read from their files
            # and uploaded only to be removed again (a fifth of a kitchen's build time).
            for link_builder in builders[0].link_builders:
                link_builder.visual_records = []
        else:  # a real object's own visuals: meshes whose materials name missing images load from a mended copy
            for record in (r for b in builders[0].link_builders for r in b.visual_records if r.type == "file"):
                if record.filename.lower().endswith(".obj"):
                    record.filename = str(loadable_visual(Path(record.filename), self._visual_cache()))
        art = builders[0].build()
        world_T_object = np.asarray(spec.world_T_object, float)
        art.set_root_pose(sapien.Pose(world_T_object @ obj.canonical_T_base))
        config = obj.configuration(spec.joint_state)
        names = [j.name for j in art.get_active_joints()]
        art.set_qpos(np.array([config.get(n, 0.0) for n in names], dtype=np.float32))
        if spec.materials:
            part_class = {name: v[0] for name, v in obj.meta.get("materials", {}).items()}
            for link in art.links:
                self._retexture_link(link.entity, obj.visual_parts.get(link.name, []), part_class, spec.materials)
        return art

    def _retexture_link(self, entity, parts, part_class: dict, materials: dict) -> None:
        sapien = self._sapien
        for comp in list(entity.components):
            if isinstance(comp, sapien.render.RenderBodyComponent):
                entity.remove_component(comp)
        if not parts:
            return
        body = sapien.render.RenderBodyComponent()
        for part in parts:
            cls = part_class.get(part.name, "painted")
            mspec = materials.get(cls) or materials["painted"]
            v, f, n, uv = uv_mesh(part.mesh, mspec.texture_scale_m)
            body.attach(sapien.render.RenderShapeTriangleMesh(v, f, n, uv, self._material(mspec)))
        entity.add_component(body)

    def _make_cameras(self) -> None:
        """One camera rig (RGB, depth/segmentation, IR pair, dot projector) per scene, moved to each view."""
        sapien = self._sapien
        desc = self.description
        if not desc.cameras:
            raise CenterArtError(f"scene {desc.scene_id} has no cameras")
        cam0 = desc.cameras[0]
        for c in desc.cameras:
            if (c.width, c.height) != (cam0.width, cam0.height) or not np.allclose(c.K, cam0.K):
                raise CenterArtError(f"scene {desc.scene_id}: all views must share one image size and K")
        w, h, K = cam0.width, cam0.height, np.asarray(cam0.K, float)
        self.K, self.width, self.height = K, w, h
        intr = Intrinsics.from_matrix(K, w, h)
        rig = sapien.Entity()
        rig.name = "camera_rig"

        shader_root = Path(sapien.__file__).parent / "vulkan_shader"

        def camera(name, shader, local_y=0.0):
            # The component wants a shader folder path, not a name; "" means the process-wide default.
            cam = sapien.render.RenderCameraComponent(w, h, str(shader_root / shader) if shader else "")
            cam.name = name
            # SAPIEN samples pixel centres at (u + 0.5, v + 0.5); K follows OpenCV (centres at integers).
            cx, cy = intr.cx + 0.5, intr.cy + 0.5
            cam.set_perspective_parameters(cam0.near, cam0.far, intr.fx, intr.fy, cx, cy, intr.skew)
            cam.local_pose = sapien.Pose([0.0, local_y, 0.0])
            rig.add_component(cam)
            return cam

        self.cam_rgb = camera("rgb", "rt" if self.shader == "rt" else "")
        self.cam_geo = camera("geometry", "") if self.shader == "rt" else self.cam_rgb
        if self.ir_cameras:
            self._add_ir_sensor(rig, camera, desc.stereo)
        self.scene.add_entity(rig)
        self.rig = rig

    def _add_ir_sensor(self, rig, camera, st) -> None:
        """The stereo sensor's IR cameras (and, for ``ir_shading="full"``, its projector) on the rig."""
        # SAPIEN's y axis points left, so an offset to the right (OpenCV +x) is -y.
        ir_shader = "trivial" if self.ir_shading == "fast" else ""  # fast: unlit albedo + position, no shadow passes
        self.cam_ir_l = camera("ir_left", ir_shader, -st.left_offset_m)
        self.cam_ir_r = camera("ir_right", ir_shader, -(st.left_offset_m + st.baseline_m))
        from centerart.scenes.depth_noise import dot_pattern

        key = (st.pattern_seed, st.pattern_dot_fraction)
        if key != self._pattern_key:
            self._pattern_key = key
            self._pattern = dot_pattern(st.pattern_seed, dot_fraction=st.pattern_dot_fraction)
            self._pattern_grey = self._pattern[..., 0].astype(np.float32) / 255.0
        if self.ir_shading == "full":
            self._add_projector(rig, st)

    def _add_projector(self, rig, st) -> None:
        """SAPIEN's textured spot light as the dot projector (``ir_shading="full"``: the IR pair is rendered lit)."""
        sapien = self._sapien
        self.projector = sapien.render.RenderTexturedLightComponent()
        self.projector.color = [0.0, 0.0, 0.0]
        fov = np.deg2rad(st.projector_fov_deg)
        self.projector.inner_fov = fov
        self.projector.outer_fov = fov
        self.projector.shadow = True
        self.projector.shadow_near = 0.1
        self.projector.shadow_far = 10.0
        self.projector.texture = sapien.render.RenderTexture2D(self._pattern, "R8G8B8A8Unorm", srgb=False)
        self.projector.local_pose = sapien.Pose([0.0, -st.projector_offset_m, 0.0])
        rig.add_component(self.projector)

    # ------------------------------------------------------------------ rendering
    def set_view(self, index: int) -> np.ndarray:
        """Move the rig to camera ``index``; returns its ``world_T_camera`` (OpenCV)."""
        pose = self.description.camera_pose(index)
        self.rig.set_pose(self._sapien.Pose(pose @ OPENCV_T_SAPIEN))
        return pose

    def render(self, index: int, ir: bool = False) -> ViewImages:
        self.set_view(index)
        scene = self.scene
        scene.update_render()
        self.cam_rgb.take_picture()
        rgb = self.cam_rgb.get_picture("Color")[..., :3]
        rgb = (np.clip(rgb, 0.0, 1.0) * 255.0 + 0.5).astype(np.uint8)
        if self.cam_geo is not self.cam_rgb:
            self.cam_geo.take_picture()
        pos = self.cam_geo.get_picture("Position")
        depth = np.where(pos[..., 3] < 1.0, -pos[..., 2], 0.0).astype(np.float32)
        seg = self.cam_geo.get_picture("Segmentation")[..., 1].astype(np.int64)
        seg = np.where(seg < len(self._entity_to_instance), seg, 0)
        images = ViewImages(rgb, depth, self._entity_to_instance[seg], self._entity_to_link_id[seg])
        if ir and not self.ir_cameras:
            raise CenterArtError("this renderer was made without the stereo sensor's IR cameras (ir_cameras=False)")
        if ir and self.ir_shading == "full":
            self._render_ir_lit(images)
        elif ir:
            self._render_ir_fast(images, index)
        return images

    def _render_ir_lit(self, images: ViewImages) -> None:
        """Both IR cameras rendered by SAPIEN's lit pipeline with the projector switched on."""
        self.projector.color = [self.description.stereo.projector_intensity] * 3
        self.scene.update_render()
        self.cam_ir_l.take_picture()
        self.cam_ir_r.take_picture()
        images.ir_left = self.cam_ir_l.get_picture("Color")[..., :3].mean(-1)
        images.ir_right = self.cam_ir_r.get_picture("Color")[..., :3].mean(-1)
        images.ir_left_depth, images.ir_right_depth = self._ir_depths()
        self.projector.color = [0.0, 0.0, 0.0]

    def _render_ir_fast(self, images: ViewImages, index: int) -> None:
        """Both IR cameras rasterised unlit (albedo, depth) and shaded by :mod:`centerart.scenes.ir_synthesis`."""
        from centerart.scenes.ir_synthesis import shade_ir

        self.cam_ir_l.take_picture()
        self.cam_ir_r.take_picture()
        images.ir_left_depth, images.ir_right_depth = self._ir_depths()
        lighting = self._ir_lighting(index)
        st = self.description.stereo
        for cam, depth, x, attr in (
            (self.cam_ir_l, images.ir_left_depth, st.left_offset_m, "ir_left"),
            (self.cam_ir_r, images.ir_right_depth, st.left_offset_m + st.baseline_m, "ir_right"),
        ):
            albedo = cam.get_picture("Color")[..., :3].mean(-1)
            setattr(images, attr, shade_ir(albedo, depth, self.K, x, lighting))

    def _ir_depths(self) -> tuple[np.ndarray, np.ndarray]:
        """True depth seen by each IR camera. The lit pipeline marks background by position.w = 1 (its depth
        buffer); the unlit ``trivial`` shader writes the homogeneous position (w = 1 on every hit) and leaves the
        background at its clear value 0, so there a hit is z < 0 (OpenGL camera frame, looking along -z)."""
        out = []
        for cam in (self.cam_ir_l, self.cam_ir_r):
            p = cam.get_picture("Position")
            hit = p[..., 3] < 1.0 if self.ir_shading == "full" else p[..., 2] < 0.0
            out.append(np.where(hit, -p[..., 2], 0.0).astype(np.float32))
        return out[0], out[1]

    def _ir_lighting(self, index: int):
        """The scene's lights and the projector in camera ``index``'s OpenCV frame, grey (IR sees no colour)."""
        from centerart.scenes.ir_synthesis import IrLighting

        desc, st = self.description, self.description.stereo
        camera_T_world = np.linalg.inv(desc.camera_pose(index))
        points, directions = [], []
        for light in desc.lights:
            grey = float(np.mean(light.color))
            if light.kind == "directional":
                directions.append((camera_T_world[:3, :3] @ np.asarray(light.direction, float), grey))
            else:  # point, and spot lights treated as points (the generated kitchens have none)
                points.append((apply_transform(camera_T_world, light.position), grey))
        return IrLighting(
            pattern=self._pattern_grey,
            projector_x=st.projector_offset_m,
            fov_deg=st.projector_fov_deg,
            intensity=st.projector_intensity,
            ambient=float(np.mean(desc.ambient)),
            point_lights=points,
            directional_lights=directions,
        )

    def _visual_cache(self) -> Path:
        """A temporary folder for mended visual meshes (:mod:`.visual_files`), removed by :meth:`close`."""
        if self._visuals is None:
            self._visuals = Path(tempfile.mkdtemp(prefix="centerart-visuals-"))
        return self._visuals

    def close(self) -> None:
        self.scene = None
        self.description = None
        if self._visuals is not None:
            shutil.rmtree(self._visuals, ignore_errors=True)
            self._visuals = None
