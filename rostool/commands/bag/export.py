"""`rostool bag export`: bags -> one Parquet/CSV table per topic, images -> PNG/MP4 (rostool[export])."""

from __future__ import annotations

from pathlib import Path

import click

from rostool.bag.export import ExportOptions
from rostool.commands.bag._options import CONTEXT, distro_option, jobs_option, topic_list, topics_option
from rostool.errors import RostoolError


@click.command(context_settings=CONTEXT)
@click.argument("bags", nargs=-1, required=True, metavar="BAG...")
@click.option(
    "--format", "fmt", type=click.Choice(["parquet", "csv"]), default="parquet", show_default=True,
    help="Table format: Parquet (typed columns, arrays as lists) or CSV (arrays as JSON text).",
)  # fmt: skip
@click.option(
    "-o", "--output", type=click.Path(file_okay=False), metavar="DIR", help="Write the tables here."
)
@topics_option
@click.option("--images", type=click.Path(file_okay=False), metavar="DIR",
              help="Write sensor_msgs Image/CompressedImage messages as PNG files here.")  # fmt: skip
@click.option("--video", is_flag=True, help="With --images: one MP4 (H.264) per image topic instead of PNGs.")
@click.option("--keep-going", is_flag=True, help="Several bags: skip the ones that fail (a warning each).")
@click.option(
    "--engine", type=click.Choice(["local", "ray"]), default="local", show_default=True,
    help="local: processes on this machine (-j). ray: a Ray task per bag, on a private local Ray started "
    "for the run, or on the cluster of --ray-address (rostool[ray]).",
)  # fmt: skip
@click.option(
    "--ray-address", metavar="ADDR", help="With --engine ray: the cluster (default: RAY_ADDRESS, else local)."
)
@jobs_option
@distro_option
def export(
    bags: tuple[str, ...],
    fmt: str,
    output: str | None,
    topics: tuple[str, ...],
    images: str | None,
    video: bool,
    keep_going: bool,
    engine: str,
    ray_address: str | None,
    jobs: int | None,
    distro: str,
) -> None:
    """Export bags to tables: one Parquet (or CSV) file per topic, for pandas, polars, DuckDB or a sheet.

    Columns: `t` (receive time, int64 ns), `stamp` (header stamp, int64 ns, when the type has a header),
    then every field, nested ones flattened (`pose.position.x`); Time fields as two integer columns
    (`header.stamp.sec`/`nanosec`, ROS 1: `secs`/`nsecs`); byte arrays (uint8[], image data) as binary;
    other arrays as typed lists in Parquet and as JSON text in CSV. One bag writes DIR/TOPIC.parquet
    (`/turtle1/pose` -> `turtle1.pose.parquet`; any character but letters, digits, `_` and `-` is written
    %XX, so no two topics share a file: `/a.b` -> `a%2Eb.parquet`). Several bags, or a directory of bags,
    write one dataset per topic partitioned by bag, hive-style: DIR/TOPIC/bag=NAME/part-0.parquet, exported
    in parallel.

    \b
    Examples:
      rostool bag export run.bag -o tables/
      rostool bag export rosbag2_dir --format csv --topics /odom,/tf -o csv/
      rostool bag export fleet/ -o dataset/ -j 2
      rostool bag export fleet/ -o dataset/ --engine ray
      rostool bag export s3://fleet/2026-11/ -o s3://analysis/dataset/ --engine ray
      rostool bag export camera.mcap --images frames/ --topics /camera/image_raw
      rostool bag export camera.mcap --images videos/ --video
      duckdb -c "SELECT bag, count(*) FROM read_parquet('dataset/odom/*/*.parquet',
                 hive_partitioning=true) GROUP BY bag"
    """
    from rostool.bag.copy_many import make_output_folder
    from rostool.bag.export import require_extras
    from rostool.bag.export_many import export_bags
    from rostool.bag.many import expand

    if output is None and images is None:
        raise RostoolError("say where to write: -o DIR for the tables and/or --images DIR for the images")
    if video and images is None:
        raise RostoolError("--video writes the images of --images DIR as MP4: add --images DIR")
    from rostool.bag.remote import is_remote, resolve

    remote_out = resolve(output) if output is not None and is_remote(output) else None
    options = ExportOptions(
        fmt=fmt if output is not None else None,  # type: ignore[arg-type]
        out=Path(output) if output is not None and remote_out is None else None,
        topics=topic_list(topics),
        images=Path(images) if images is not None else None,
        video=video,
        distro=distro,
    )
    require_extras(options)
    items = expand(bags)
    if remote_out is not None:
        options.out = Path("-")  # each bag is written into a local folder of its own, then uploaded
    for where in (options.out if remote_out is None else None, options.images):
        if where is not None:
            make_output_folder(where)
    runner = None
    if engine == "ray":
        from rostool.bag.ray_engine import runner as ray_runner

        runner = ray_runner(ray_address)
    elif ray_address:
        raise RostoolError("--ray-address is for --engine ray")
    total, exported = export_bags(items, options, remote_out, jobs, keep_going, runner)
    outputs = (remote_out if remote_out is not None else options.out, options.images)
    where = " and ".join(str(p) for p in outputs if p is not None)
    bags_text = f" from {exported} bags" if len(items) > 1 else ""
    pictures = f" ({total.images} images)" if options.images is not None else ""
    click.echo(f"exported {total.messages} messages{bags_text}{pictures} to {where}", err=True)
