"""Types of the names ``px4params`` imports on first use (see ``__init__.py``)."""

from px4params.dsdl.schema import (
    DataType as DataType,
)
from px4params.dsdl.schema import (
    Leaf as Leaf,
)
from px4params.dsdl.schema import (
    Schema as Schema,
)
from px4params.dsdl.schema import (
    StructValue as StructValue,
)
from px4params.dsdl.schema import (
    load_schema as load_schema,
)
from px4params.dsdl.schema import (
    to_json_value as to_json_value,
)
from px4params.errors import (
    CodecError as CodecError,
)
from px4params.errors import (
    CommandError as CommandError,
)
from px4params.errors import (
    DecodeError as DecodeError,
)
from px4params.errors import (
    DeviceIdError as DeviceIdError,
)
from px4params.errors import (
    DsdlError as DsdlError,
)
from px4params.errors import (
    EncodeError as EncodeError,
)
from px4params.errors import (
    InstanceError as InstanceError,
)
from px4params.errors import (
    LeafError as LeafError,
)
from px4params.errors import (
    Px4ParamsError as Px4ParamsError,
)
from px4params.errors import (
    StoreError as StoreError,
)
from px4params.errors import (
    StoreFileError as StoreFileError,
)
from px4params.errors import (
    TransferError as TransferError,
)
from px4params.errors import (
    ValueRangeError as ValueRangeError,
)
from px4params.errors import (
    ValueShapeError as ValueShapeError,
)
from px4params.store.key import (
    Key as Key,
)
from px4params.store.store import (
    InstanceView as InstanceView,
)
from px4params.store.store import (
    Store as Store,
)

__all__: list[str]
__version__: str
