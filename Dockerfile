# tresca-feti on Debian 12 with Rust. The system packages come from run/packages.txt, the same
# list run/demo and run/test install from.
#   docker build -t tresca-feti .
#   docker run --rm -v "$PWD/out:/work/out" tresca-feti solve run/seed.toml
#   docker run --rm --entrypoint mpirun tresca-feti -n 2 tresca-feti solve run/seed.toml
FROM rust:1-bookworm
WORKDIR /work
COPY run/packages.txt run/install-deps run/
RUN run/install-deps && rm -rf /var/lib/apt/lists/*
COPY . .
RUN cargo build --release && cp target/release/tresca-feti /usr/local/bin/ && rm -rf target
ENV OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
ENTRYPOINT ["tresca-feti"]
