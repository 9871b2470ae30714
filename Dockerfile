# knotsweep in a container: `docker compose up` (docker-compose.yml) runs PostgreSQL, the server and workers.
# Build stage: the release binary, with the web page and migrations embedded.
FROM rust:1.85-bookworm AS build
WORKDIR /src
COPY . .
RUN cargo build --release --locked --bin knotsweep && strip target/release/knotsweep

# Runtime stage: the binary alone on a slim Debian, as an unprivileged user.
FROM debian:bookworm-slim
RUN apt-get update && apt-get install -y --no-install-recommends ca-certificates curl \
    && rm -rf /var/lib/apt/lists/* \
    && useradd --system --home-dir /var/lib/knotsweep --create-home knotsweep
COPY --from=build /src/target/release/knotsweep /usr/local/bin/knotsweep
USER knotsweep
WORKDIR /var/lib/knotsweep
EXPOSE 8080
ENTRYPOINT ["knotsweep"]
CMD ["serve", "--addr", "0.0.0.0:8080"]
