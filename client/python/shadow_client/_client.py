"""A small Python client for shadow.v1.ShadowService (see the package docstring)."""

from __future__ import annotations

import dataclasses
import hashlib
import random
import time
from typing import Callable, Iterable, Iterator, Optional, Sequence, Union

import grpc
import numpy as np

from ._proto.shadow.v1 import shadow_pb2 as pb
from ._proto.shadow.v1 import shadow_pb2_grpc as pb_grpc
from ._targets import channel_target, first_host, service_config_json, target_of_one

# Largest reply message accepted; the server sends 2 MiB chunks (as the C++ client).
MAX_RECEIVE_BYTES = 64 << 20
# Refuse a reply whose header announces more than this many texture bytes.
MAX_TOTAL_BYTES = 8 << 30
# How render() and sequence() resume a reply that broke off (UNAVAILABLE: its server died;
# INTERNAL: a proxy reset it), as the C++ client does: before the n-th resume of a call (n = 0,
# 1, ...; a sequence counts from its last stream that delivered a frame) they sleep a pause drawn
# uniformly from [0, min(RESUME_BACKOFF_MAX, RESUME_BACKOFF_INITIAL * RESUME_BACKOFF_MULTIPLIER **
# n)] seconds ("full jitter": clients cut off by the same crash do not all come back at once), then
# call again with wait_for_ready, so that while the server is down (restarting) the call waits for
# the channel to connect instead of failing at once. Resumes go on while the call's timeout
# allows, however many it takes; none starts whose pause would pass it. A call without a timeout
# (timeout=None) waits for the server as long as it takes, as any call without a deadline does, but
# resumes at most MAX_RESUMES_WITHOUT_TIMEOUT times (a server that breaks every stream is not
# tried for ever). The channel's reconnect backoff is capped at RESUME_BACKOFF_MAX too, so a server
# that comes back is seen within about that long (gRPC's default grows to 120 s).
RESUME_BACKOFF_INITIAL = 0.1
RESUME_BACKOFF_MULTIPLIER = 2
RESUME_BACKOFF_MAX = 2.0
MAX_RESUMES_WITHOUT_TIMEOUT = 10
# gRPC keeps a call's request for its retries only up to this size (as the C++ client).
RETRY_BUFFER_BYTES = 64 << 20
# UploadScene chunks (the server takes a scene's serialization in as many as it needs).
UPLOAD_CHUNK_BYTES = 2 << 20
SCENE_ID_HEADER = "x-scene-id"


def scene_key(scene: pb.Scene) -> str:
    """SHA-256 (hex) of the scene's deterministic serialization, the same key the C++ client
    sends as x-scene-id and UploadScene returns (wire/scene_id.hpp)."""
    return hashlib.sha256(scene.SerializeToString(deterministic=True)).hexdigest()


class RpcError(Exception):
    """A failed call: `code` is the grpc.StatusCode, the message names the bad field."""

    def __init__(self, code: grpc.StatusCode, message: str):
        super().__init__(f"{code.name}: {message}")
        self.code = code
        self.message = message


@dataclasses.dataclass
class CubeFace:
    name: str  # "+x" .. "-z"
    world_to_ndc: np.ndarray  # 4x4 float32, column-vector: ndc ~ M @ [x, y, z, 1]
    world_to_camera: np.ndarray


@dataclasses.dataclass
class AtlasTile:
    instance: int  # index in the scene's instances
    x: int  # texel (x + u * size, y + v * size) holds the mesh's point at UV (u, v)
    y: int
    size: int
    texel_world_size: float = 0.0  # at most, on the instance's surface


@dataclasses.dataclass
class Texture:
    """One product. `data` is (height, width, channels), or (faces, height, width, channels) for a
    cube texture, float32, float16 (RenderRequest.pixel_format) or float64 (SATs), row 0 at the
    top. `world_to_ndc` maps world points
    (column vectors, w = 1) to the texture: after division by w, x and y run 0..1 across the image
    from its top-left corner and z is the stored depth. A cube texture's matrices are per face."""

    name: str  # "shadowmap", "visibility", "position", "shadowmap_mip3", "shadowmap_cube", ...
    kind: int  # shadow_pb2.Product value; pb.Product.Name(kind) spells it
    data: np.ndarray
    world_to_ndc: np.ndarray
    world_to_camera: np.ndarray
    cube_faces: list[CubeFace]
    channel_names: list[str]  # CSM bases: one name per channel, in data order
    depth_mapping: str  # how the stored depth relates to NDC z, for textures where it differs
    csm_terms: int
    light: int  # index in RenderRequest.lights of its light (0 for POSITION)
    atlas_tiles: list["AtlasTile"]  # PRODUCT_SHADOW_ATLAS: each receiving instance's tile
    mesh: int  # PRODUCT_ATLAS_UVS: the mesh whose generated layout `data` holds (3 corners a row)

    @property
    def is_cube(self) -> bool:
        return self.data.ndim == 4


@dataclasses.dataclass
class VirtualPages:
    """TECHNIQUE_VIRTUAL's pages in a reply (RenderHeader.virtual_pages), summed over its
    lights."""

    requested: int  # the pages the camera's pixels marked
    resident: int  # those held in the pool
    rendered: int  # those drawn for this reply (the rest were kept from an earlier frame)
    coarsened_pixels: int  # pixels that read a coarser level because the pool was full
    pool_bytes: int  # the pool's size


@dataclasses.dataclass
class RenderResult:
    """The textures in the order of the request's products (a *_MIPS product gives one per level),
    and the reply header (passes, device timings, the light fit's report)."""

    textures: list[Texture]
    header: pb.RenderHeader
    frame: int = 0  # sequences: the frame's index in the request's frames

    @property
    def reused(self) -> list[str]:
        """Sequences: the passes kept from an earlier frame (their inputs did not change)."""
        return list(self.header.reused)

    @property
    def rerun(self) -> list[str]:
        """Sequences: the passes that could have been kept but ran again (an input changed)."""
        return list(self.header.rerun)

    @property
    def virtual_pages(self) -> Optional[VirtualPages]:
        """TECHNIQUE_VIRTUAL's page counts (every frame of a sequence has its own); None with
        the other techniques."""
        if not self.header.HasField("virtual_pages"):
            return None
        v = self.header.virtual_pages
        return VirtualPages(v.requested, v.resident, v.rendered, v.coarsened_pixels, v.pool_bytes)

    def __getitem__(self, name: str) -> Texture:
        for t in self.textures:
            if t.name == name:
                return t
        raise KeyError(f"no texture {name!r} (have {', '.join(t.name for t in self.textures)})")


def _matrix(m: pb.Mat4) -> np.ndarray:
    """A Mat4 (16 floats, column-major) as a 4x4 array indexed [row, column]."""
    if len(m.m) == 0:
        return np.eye(4, dtype=np.float32)
    if len(m.m) != 16:
        raise RpcError(grpc.StatusCode.DATA_LOSS, f"a matrix has {len(m.m)} values, not 16")
    return np.array(m.m, dtype=np.float32).reshape(4, 4).T.copy()


def _read_pem(path: Optional[str]) -> Optional[bytes]:
    if not path:
        return None
    with open(path, "rb") as f:
        return f.read()


class _Assembler:
    """Puts a Render stream back together, holding it to the protocol in shadow.proto (header
    first, each texture's chunks in order and contiguous, exactly byte_size bytes). Any break is
    DATA_LOSS, as in the C++ client."""

    def __init__(self):
        self.header: Optional[pb.RenderHeader] = None
        self.buffers: list[bytearray] = []
        self.received: list[int] = []

    @staticmethod
    def _broken(what: str) -> RpcError:
        return RpcError(grpc.StatusCode.DATA_LOSS, "bad Render stream: " + what)

    def add(self, response: pb.RenderResponse) -> None:
        kind = response.WhichOneof("payload")
        if kind == "header":
            if self.header is not None:
                raise self._broken("a second header arrived")
            self.header = response.header
            total = sum(info.byte_size for info in self.header.textures)
            if total > MAX_TOTAL_BYTES:
                raise self._broken(f"the textures would take more than {MAX_TOTAL_BYTES} bytes")
            for info in self.header.textures:
                expected = _shape_bytes(info)
                if expected != info.byte_size:
                    raise self._broken(
                        f"{info.name} declares {info.byte_size} bytes, its shape {expected}")
            self.buffers = [bytearray(info.byte_size) for info in self.header.textures]
            self.received = [0] * len(self.buffers)
        elif kind == "chunk":
            c = response.chunk
            if self.header is None:
                raise self._broken("a chunk arrived before the header")
            if c.texture >= len(self.buffers):
                raise self._broken(f"a chunk names texture {c.texture} of {len(self.buffers)}")
            if c.compression == pb.CHUNK_COMPRESSION_ZSTD:
                raise self._broken("a zstd chunk, though the request did not allow them")
            got = self.received[c.texture]
            if c.offset != got:
                raise self._broken(f"texture {c.texture}: a chunk at {c.offset}, expected {got}")
            end = got + len(c.data)
            if end > len(self.buffers[c.texture]):
                raise self._broken(f"texture {c.texture}: chunks run past its byte_size")
            self.buffers[c.texture][got:end] = c.data
            self.received[c.texture] = end
        else:
            raise self._broken("a response carries neither a header nor a chunk")

    def finish(self) -> RenderResult:
        if self.header is None:
            raise self._broken("the stream ended before the header")
        textures = []
        for i, info in enumerate(self.header.textures):
            if self.received[i] != info.byte_size:
                raise self._broken(
                    f"{info.name}: {self.received[i]} of {info.byte_size} bytes arrived")
            textures.append(_texture(info, self.buffers[i]))
        return RenderResult(textures=textures, header=self.header, frame=self.header.frame)


def _remaining(deadline: Optional[float]) -> Optional[float]:
    """Seconds left until a time.monotonic() deadline; None: no deadline."""
    return None if deadline is None else max(deadline - time.monotonic(), 0)


def _chain(head: RenderResult, rest: Iterator[RenderResult]) -> Iterator[RenderResult]:
    yield head
    yield from rest


def _faces(info: pb.TextureInfo) -> int:
    return len(info.cube_faces) if len(info.cube_faces) else max(info.faces, 1)


def _dtype(info: pb.TextureInfo) -> np.dtype:
    return np.dtype({pb.PIXEL_FORMAT_FLOAT64: "<f8", pb.PIXEL_FORMAT_FLOAT16: "<f2"}.get(
        info.format, "<f4"))


def _shape_bytes(info: pb.TextureInfo) -> int:
    return info.width * info.height * max(info.channels, 1) * _faces(info) * _dtype(info).itemsize


def _texture(info: pb.TextureInfo, raw: bytearray) -> Texture:
    shape = (info.height, info.width, max(info.channels, 1))
    is_cube = len(info.cube_faces) > 0 or info.faces != 1
    if is_cube:
        shape = (_faces(info),) + shape
    # Little-endian on the wire; native order in the array.
    data = np.frombuffer(raw, dtype=_dtype(info)).reshape(shape)
    data = data.astype(data.dtype.newbyteorder("="), copy=False)
    return Texture(
        name=info.name,
        kind=info.kind,
        data=data,
        world_to_ndc=_matrix(info.world_to_ndc),
        world_to_camera=_matrix(info.world_to_camera),
        cube_faces=[CubeFace(f.name, _matrix(f.world_to_ndc), _matrix(f.world_to_camera))
                    for f in info.cube_faces],
        channel_names=list(info.channel_names),
        depth_mapping=info.depth_mapping,
        csm_terms=info.csm_terms,
        atlas_tiles=[AtlasTile(a.instance, a.x, a.y, a.size, a.texel_world_size)
                     for a in info.atlas_tiles],
        light=info.light,
        mesh=info.mesh,
    )


def _asking_progress(request: pb.RenderRequest) -> pb.RenderRequest:
    """A copy of `request` that asks for Progress messages (the caller's stays as it was)."""
    asked = pb.RenderRequest()
    asked.CopyFrom(request)
    asked.progress = True
    return asked


def _took_progress(response: pb.RenderResponse,
                   progress: Optional[Callable[[pb.Progress], None]]) -> bool:
    """True for a Progress message, passed to `progress` if given; False for anything else."""
    if response.WhichOneof("payload") != "progress":
        return False
    if progress is not None:
        progress(response.progress)
    return True


class Client:
    """A client of one server, or of several replicas balanced round-robin.

    target: "HOST:PORT", a list of "HOST:PORT" (gRPC's round_robin over them), or any gRPC
    target ("dns:///shadow.example:50051": round_robin over what the name resolves to). With
    several replicas a call that fails UNAVAILABLE before any reply is retried on another
    (gRPC's retry policy in the service config).
    tls_ca, tls_cert, tls_key, token: as shadowctl's --tls-ca, --tls-cert, --tls-key, --token
    (PEM files; any of them means TLS; the token is sent as "authorization: Bearer TOKEN").
    tls_server_name: the name the server's certificate must carry; by default the target's host
    (with several targets, the first one's).
    """

    def __init__(self, target: Union[str, Sequence[str]], *, tls_ca: Optional[str] = None,
                 tls_cert: Optional[str] = None, tls_key: Optional[str] = None,
                 token: Optional[str] = None, tls_server_name: Optional[str] = None):
        options = [
            ("grpc.max_receive_message_length", MAX_RECEIVE_BYTES),
            ("grpc.max_send_message_length", -1),
            ("grpc.service_config", service_config_json()),
            ("grpc.enable_retries", 1),
            ("grpc.per_rpc_retry_buffer_size", RETRY_BUFFER_BYTES),
            ("grpc.max_reconnect_backoff_ms", int(RESUME_BACKOFF_MAX * 1000)),
        ]
        address = channel_target(target)
        if tls_server_name or address != target_of_one(target):
            options.append(("grpc.default_authority", tls_server_name or first_host(target)))
        if tls_ca or tls_cert or tls_key or token:
            if bool(tls_cert) != bool(tls_key):
                raise ValueError("a client certificate needs both tls_cert and tls_key")
            credentials = grpc.ssl_channel_credentials(
                root_certificates=_read_pem(tls_ca), private_key=_read_pem(tls_key),
                certificate_chain=_read_pem(tls_cert))
            if token:
                credentials = grpc.composite_channel_credentials(
                    credentials, grpc.access_token_call_credentials(token))
            self._channel = grpc.secure_channel(address, credentials, options=options)
        else:
            self._channel = grpc.insecure_channel(address, options=options)
        self._stub = pb_grpc.ShadowServiceStub(self._channel)
        self.stream_restarts = 0  # replies asked for again after they broke off
        self.scene_reuploads = 0  # scenes uploaded again because a replica did not hold them
        self._uploaded: dict[str, pb.Scene] = {}  # by id, for re-uploads

    def close(self) -> None:
        self._channel.close()

    def __enter__(self) -> "Client":
        return self

    def __exit__(self, *exc) -> None:
        self.close()

    def wait_ready(self, timeout: float = 30.0) -> None:
        """Blocks until the channel connects; raises grpc.FutureTimeoutError past `timeout`."""
        grpc.channel_ready_future(self._channel).result(timeout=timeout)

    @staticmethod
    def _pause_before_resume(step: int, resumes: int, deadline: Optional[float]) -> bool:
        """Sleeps before the `step`-th resume of a call (from 0; see RESUME_BACKOFF_INITIAL),
        which has resumed `resumes` times so far. False, without sleeping, when no resume is
        left: the pause would reach `deadline`, or, without one, MAX_RESUMES_WITHOUT_TIMEOUT
        are spent."""
        ceiling = min(RESUME_BACKOFF_MAX,
                      RESUME_BACKOFF_INITIAL * RESUME_BACKOFF_MULTIPLIER ** min(step, 64))
        pause = random.uniform(0, ceiling)
        if deadline is None and resumes >= MAX_RESUMES_WITHOUT_TIMEOUT:
            return False
        if deadline is not None and time.monotonic() + pause >= deadline:
            return False
        time.sleep(pause)
        return True

    def render(self, request: pb.RenderRequest, timeout: Optional[float] = 300.0,
               progress: Optional[Callable[[pb.Progress], None]] = None) -> RenderResult:
        """As _render, with a re-upload when a request by scene_id finds the server without
        the scene this client uploaded (upload_scene()). With `progress`, the request asks for
        progress (RenderRequest.progress) and each pb.Progress message is passed to it while
        the server renders (phase, fraction, device_ms, estimate_ms), for work predicted over
        half a second; what it raises cancels the call."""
        if progress is not None:
            request = _asking_progress(request)
        scene_id = "" if request.HasField("scene") else request.scene_id
        return self._with_scene(scene_id, timeout,
                                lambda: self._render(request, timeout, progress))

    def _render(self, request: pb.RenderRequest, timeout: Optional[float],
                progress: Optional[Callable[[pb.Progress], None]] = None) -> RenderResult:
        """Sends one RenderRequest and returns every product as numpy arrays. Raises RpcError
        with the server's status (INVALID_ARGUMENT names the field), or DATA_LOSS when the
        stream breaks the protocol. As the C++ client: the request carries its scene_key() as
        "x-scene-id" metadata, and a reply that breaks off after it began, UNAVAILABLE (its
        replica died) or INTERNAL (a proxy such as nginx reset it), is asked for again with the
        backoff of RESUME_BACKOFF_INITIAL, within `timeout` (None: no deadline); a resumed call
        that fails the same way, even before its first reply (the server may still be on its way
        back), is resumed again. Resumes are counted in `stream_restarts`."""
        if request.chunk_compression == pb.CHUNK_COMPRESSION_ZSTD:
            raise ValueError("chunk_compression: this client takes raw chunks only (NONE)")
        scene_id = scene_key(request.scene) if request.HasField("scene") else request.scene_id
        metadata = ((SCENE_ID_HEADER, scene_id),) if scene_id else ()
        deadline = None if timeout is None else time.monotonic() + timeout
        resumes = 0
        while True:
            assembler = _Assembler()
            call = self._stub.Render(request, timeout=_remaining(deadline),
                                     metadata=metadata, wait_for_ready=resumes > 0)
            try:
                for response in call:
                    if _took_progress(response, progress):
                        continue
                    assembler.add(response)
                return assembler.finish()
            except grpc.RpcError as e:
                broke = e.code() in (grpc.StatusCode.UNAVAILABLE, grpc.StatusCode.INTERNAL)
                if (not broke or (assembler.header is None and resumes == 0)
                        or not self._pause_before_resume(resumes, resumes, deadline)):
                    raise RpcError(e.code(), e.details() or "") from None
                resumes += 1
                self.stream_restarts += 1
            except RpcError:
                call.cancel()
                raise

    def upload_scene(self, scene: pb.Scene, timeout: Optional[float] = 300.0) -> str:
        """UploadScene: sends the scene in chunks and returns its id (scene_key()). The client
        keeps the scene: a later request by that id that finds a server without it (NOT_FOUND:
        evicted, or another replica) uploads it again and is retried once
        (`scene_reuploads`)."""
        data = scene.SerializeToString(deterministic=True)
        scene_id = scene_key(scene)

        def chunks():
            for offset in range(0, max(len(data), 1), UPLOAD_CHUNK_BYTES):
                chunk = pb.SceneUpload(data=data[offset:offset + UPLOAD_CHUNK_BYTES])
                if offset == 0:
                    chunk.total_bytes = len(data)
                yield chunk

        try:
            ref = self._stub.UploadScene(chunks(), timeout=timeout,
                                         metadata=((SCENE_ID_HEADER, scene_id),))
        except grpc.RpcError as e:
            raise RpcError(e.code(), e.details() or "") from None
        if ref.scene_id != scene_id:
            raise RpcError(grpc.StatusCode.DATA_LOSS,
                           f"the server's scene id {ref.scene_id} is not the scene's {scene_id}")
        self._uploaded[scene_id] = scene
        return scene_id

    def _with_scene(self, scene_id: str, timeout: Optional[float], call):
        """Runs call(); when a request by `scene_id` finds the server without the scene and this
        client uploaded it, uploads it again and runs call() once more."""
        try:
            return call()
        except RpcError as e:
            if e.code != grpc.StatusCode.NOT_FOUND or scene_id not in self._uploaded:
                raise
            self.upload_scene(self._uploaded[scene_id], timeout)
            self.scene_reuploads += 1
            return call()

    def sequence(self, request: pb.SequenceRequest, timeout: Optional[float] = 1800.0,
                 progress: Optional[Callable[[pb.Progress], None]] = None
                 ) -> Iterator[RenderResult]:
        """RenderSequence: yields each frame's RenderResult (`frame`, `reused`) as it arrives, in
        order. A stream that breaks off (UNAVAILABLE: its replica died; INTERNAL: a proxy reset
        it), before or after its first frame, is resumed with the frames not yet delivered, with
        the backoff of RESUME_BACKOFF_INITIAL, within `timeout` (None: no deadline), so every
        frame arrives once; a replica without the scene gets it uploaded again. `progress` as
        render()'s, with frames_done of frames (counted in the stream that is running)."""
        base = request.base
        if progress is not None:
            base = _asking_progress(base)
        scene_id = scene_key(base.scene) if base.HasField("scene") else base.scene_id
        deadline = None if timeout is None else time.monotonic() + timeout
        delivered = 0
        resumes = 0
        backoff_step = 0  # resumes since a stream last delivered a frame
        while True:
            rest = pb.SequenceRequest(base=base, frames=request.frames[delivered:])
            first = delivered
            resumed = resumes > 0  # this stream waits for the channel to connect

            def frames():
                call = self._stub.RenderSequence(
                    rest, timeout=_remaining(deadline),
                    metadata=((SCENE_ID_HEADER, scene_id),) if scene_id else (),
                    wait_for_ready=resumed)
                assembler = None
                try:
                    for response in call:
                        if _took_progress(response, progress):
                            continue
                        if response.WhichOneof("payload") == "header" and assembler is not None:
                            yield assembler.finish()
                            assembler = None
                        if assembler is None:
                            assembler = _Assembler()
                        assembler.add(response)
                    if assembler is not None:
                        yield assembler.finish()
                except grpc.RpcError as e:
                    raise RpcError(e.code(), e.details() or "") from None
                finally:
                    call.cancel()

            stream = iter(())

            def first_frame():  # of a new stream: a re-upload's retry starts another
                nonlocal stream
                stream = frames()
                return next(stream, None)

            try:
                # The server looks the scene up before it renders: NOT_FOUND comes first.
                head = self._with_scene(base.scene_id if not base.HasField("scene") else "",
                                        timeout, first_frame)
                if head is None:
                    return
                for result in _chain(head, stream):
                    result.frame += first
                    delivered += 1
                    yield result
                return
            except RpcError as e:
                broke = e.code in (grpc.StatusCode.UNAVAILABLE, grpc.StatusCode.INTERNAL)
                if delivered > first:  # a healthy stream: the next pause is the shortest again
                    backoff_step = 0
                if not broke or not self._pause_before_resume(backoff_step, resumes, deadline):
                    raise
                backoff_step += 1
                resumes += 1
                self.stream_restarts += 1

    def estimate(self, work: Union[pb.RenderRequest, pb.SequenceRequest],
                 timeout: float = 30.0) -> pb.Price:
        """Estimate: the server's price of a request or a whole sequence without rendering it
        (estimated device time, memory and reply bytes, its limits, and whether it would be
        admitted: Price.admitted, else Price.refused_field and Price.refusal)."""
        request = (pb.EstimateRequest(sequence=work) if isinstance(work, pb.SequenceRequest)
                   else pb.EstimateRequest(render=work))
        try:
            return self._stub.Estimate(request, timeout=timeout)
        except grpc.RpcError as e:
            raise RpcError(e.code(), e.details() or "") from None

    def statistics(self, timeout: float = 10.0) -> pb.Statistics:
        """GetStatistics (with tokens: this tenant's only)."""
        try:
            return self._stub.GetStatistics(pb.StatisticsRequest(), timeout=timeout)
        except grpc.RpcError as e:
            raise RpcError(e.code(), e.details() or "") from None
