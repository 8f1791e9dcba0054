"""shadow_client: a Python client for shadow-server (shadow.v1.ShadowService).

    import shadow_client as sc
    with sc.Client("127.0.0.1:50051") as client:          # or tls_ca=, token=, several targets
        request = sc.pb.RenderRequest(...)                 # the wire API, proto/shadow/v1
        result = client.render(request)
        vis = result["visibility"].data                   # numpy (height, width, 1), float32
        m = result["shadowmap"].world_to_ndc               # 4x4, ndc ~ m @ [x, y, z, 1]
        scene_id = client.upload_scene(scene)              # then RenderRequest(scene_id=...)
        for frame in client.sequence(sc.pb.SequenceRequest(base=..., frames=[...])):
            ...                                            # each frame as it arrives

`pb` is the generated shadow.v1 module (messages and enums); `mesh` packs numpy arrays
into a Mesh's little-endian byte fields; `VirtualShadowMap` reads PRODUCT_VIRTUAL_PAGES and
samples the pool through a light's page tables.
"""

from ._client import (AtlasTile, Client, CubeFace, RenderResult, RpcError, Texture,  # noqa: F401
                      VirtualPages, scene_key)
from ._proto.shadow.v1 import shadow_pb2 as pb  # noqa: F401
from ._targets import channel_target  # noqa: F401
from ._mesh import mesh  # noqa: F401
from ._virtual_pages import VirtualShadowMap  # noqa: F401
